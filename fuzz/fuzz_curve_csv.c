/* libFuzzer target for the CSV polyline reader and the curve flow's input
 * checks (see fuzz_curve.h). */
#include "fuzz_curve.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_curve(data, size, 0);
}
