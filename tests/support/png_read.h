/*
 * Reading PNG files back in tests (Debian's stb_image, PNG only), so that
 * only one translation unit compiles the decoder.
 */
#ifndef CF_TESTS_PNG_READ_H
#define CF_TESTS_PNG_READ_H

/* RGB pixels (3 bytes each, rows top to bottom) of a PNG file, with its size
 * in *width / *height; NULL if it cannot be read. Free with cft_png_free. */
unsigned char *cft_png_load_rgb(const char *path, int *width, int *height);
void cft_png_free(unsigned char *pixels);

#endif /* CF_TESTS_PNG_READ_H */
