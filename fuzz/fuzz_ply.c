/* libFuzzer target for the PLY reader (see fuzz_reader.h). */
#include "fuzz_reader.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_reader(data, size, CF_FORMAT_PLY, "fuzz.ply");
}
