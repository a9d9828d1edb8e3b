/* libFuzzer target for the SVG polyline reader (polygon, polyline, path with
 * M L H V C S Q T A Z, rect, circle, ellipse) and the curve flow's input
 * checks (see fuzz_curve.h). */
#include "fuzz_curve.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_curve(data, size, 1);
}
