#include "render/image.h"

#include <png.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "render/gl_api.h"
#include "render/render_error.h"

namespace fp::render {

Image readFramebuffer(unsigned framebuffer, int x, int y, int width, int height) {
  Image image;
  image.width = width;
  image.height = height;
  image.rgba.resize(std::size_t(width) * std::size_t(height) * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  std::vector<std::uint8_t> bottomUp(image.rgba.size());
  glReadPixels(x, y, width, height, GL_RGBA, GL_UNSIGNED_BYTE, bottomUp.data());
  gl::checkError("glReadPixels");
  const std::size_t row = std::size_t(width) * 4;
  for (int r = 0; r < height; ++r)
    std::copy_n(&bottomUp[std::size_t(height - 1 - r) * row], row, &image.rgba[std::size_t(r) * row]);
  return image;
}

namespace {
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// libpng's default handlers print to stderr; these keep the message for the one-line error instead (in a
// thread-local, not a local of writePng: a local changed between setjmp and longjmp would be indeterminate)
thread_local std::string t_pngMessage;
void pngError(png_structp png, png_const_charp message) {
  t_pngMessage = message;
  png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}
}  // namespace

void writePng(const std::string& path, const Image& image) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
  if (!file)
    throw RenderError(path + ": cannot write the image");
  t_pngMessage.clear();
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, pngError, pngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw RenderError(path + ": cannot start a PNG encoder");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw RenderError(path + ": writing the PNG failed" +
                      (t_pngMessage.empty() ? "" : " (" + t_pngMessage + ")"));
  }
  png_init_io(png, file.get());
  // speed over size: frames of a long run are written on every frame
  png_set_compression_level(png, 3);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB_ALPHA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int r = 0; r < image.height; ++r)
    png_write_row(png, image.rgba.data() + std::size_t(r) * std::size_t(image.width) * 4);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(file.get()) != 0)
    throw RenderError(path + ": writing the image failed");
}

Image readPng(const std::string& path) {
  png_image decoder{};
  decoder.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&decoder, path.c_str()))
    throw RenderError(path + ": cannot read the PNG (" + decoder.message + ")");
  decoder.format = PNG_FORMAT_RGBA;
  Image image;
  image.width = int(decoder.width);
  image.height = int(decoder.height);
  image.rgba.resize(PNG_IMAGE_SIZE(decoder));
  if (!png_image_finish_read(&decoder, nullptr, image.rgba.data(), 0, nullptr)) {
    const std::string message = decoder.message;
    png_image_free(&decoder);
    throw RenderError(path + ": cannot decode the PNG (" + message + ")");
  }
  return image;
}

ImageDiff compareImages(const Image& a, const Image& b, int pixelTolerance) {
  if (a.width != b.width || a.height != b.height)
    throw RenderError("images of different sizes: " + std::to_string(a.width) + "x" +
                      std::to_string(a.height) + " and " + std::to_string(b.width) + "x" +
                      std::to_string(b.height));
  ImageDiff diff;
  const std::size_t pixels = std::size_t(a.width) * std::size_t(a.height);
  double sum = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(a.rgba[p * 4 + c]) - int(b.rgba[p * 4 + c]));
      worst = std::max(worst, d);
      sum += d;
    }
    diff.maxDifference = std::max(diff.maxDifference, worst);
    if (worst > pixelTolerance)
      ++diff.pixelsOver;
  }
  diff.meanDifference = pixels ? sum / double(pixels * 3) : 0.0;
  diff.fractionOver = pixels ? double(diff.pixelsOver) / double(pixels) : 0.0;
  return diff;
}

}  // namespace fp::render
