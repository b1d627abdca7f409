#pragma once
/// RGBA8 images: read back from a framebuffer, written to and read from PNG, and compared under a stated
/// tolerance (the image tests).

#include <cstdint>
#include <string>
#include <vector>

namespace fp::render {

/// An 8-bit RGBA image, rows from the top.
struct Image {
  int width = 0;                   ///< pixels
  int height = 0;                  ///< pixels
  std::vector<std::uint8_t> rgba;  ///< width * height * 4 bytes, row-major from the top-left

  /// pointer to the four bytes of pixel (x, y), y from the top
  const std::uint8_t* at(int x, int y) const { return &rgba[(std::size_t(y) * std::size_t(width) + x) * 4]; }
};

/// Reads the colour of `framebuffer` (0: the context's) inside the rectangle into an image; a GL context must
/// be current.
Image readFramebuffer(unsigned framebuffer, int x, int y, int width, int height);

/// Writes an image as PNG; throws RenderError naming the file when it cannot be written.
void writePng(const std::string& path, const Image& image);
/// Reads a PNG as RGBA8; throws RenderError naming the file when it is missing or not a PNG.
Image readPng(const std::string& path);

/// How far two images of one size differ, over the RGB channels.
struct ImageDiff {
  int maxDifference = 0;       ///< largest channel difference of any pixel [0, 255]
  double meanDifference = 0;   ///< mean absolute channel difference [0, 255]
  std::size_t pixelsOver = 0;  ///< pixels with a channel difference above the per-pixel tolerance
  double fractionOver = 0;     ///< pixelsOver / pixel count
};

/// Compares two images of the same size; `pixelTolerance` is the channel difference a pixel may have.
ImageDiff compareImages(const Image& a, const Image& b, int pixelTolerance);

}  // namespace fp::render
