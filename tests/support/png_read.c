/* PNG reading for tests (png_read.h) on Debian's stb_image. */
#include "png_read.h"

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wmissing-prototypes"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#pragma GCC diagnostic ignored "-Wtype-limits"
#endif
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
/* stb declares static functions it defines only when asked for them */
#pragma GCC diagnostic ignored "-Wunused-function"
#endif

unsigned char *cft_png_load_rgb(const char *path, int *width, int *height)
{
    int channels = 0;
    return stbi_load(path, width, height, &channels, 3);
}

void cft_png_free(unsigned char *pixels) { stbi_image_free(pixels); }
