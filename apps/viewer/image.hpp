// RGB images in memory (top row first), written as PNG, with text labels drawn on
// the CPU (stb_easy_font), so labelling needs no font texture.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace wetcloth::viewer {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // width * height * 3, top row first

  Image() = default;
  Image(int w, int h, std::uint8_t fill = 0)
      : width(w), height(h), rgb(static_cast<std::size_t>(w) * h * 3, fill) {}
  std::uint8_t* pixel(int x, int y) { return &rgb[(static_cast<std::size_t>(y) * width + x) * 3]; }
};

// Writes path whole or not at all (temporary name, then rename). False on failure.
bool write_png(const std::filesystem::path& path, const Image& img);

// Copies src into dst with its top-left corner at (x, y), clipped.
void blit(Image& dst, const Image& src, int x, int y);

// Blends colour c over the rectangle [x0, x1) x [y0, y1) with opacity a, clipped.
void fill_rect(Image& img, int x0, int y0, int x1, int y1, const std::uint8_t c[3], float a);

// Draws text (ASCII; other characters become '?') at (x, y), scale pixels per font
// unit, white on a translucent dark box.
void draw_label(Image& img, int x, int y, const std::string& text, int scale);
// The size of that box, in pixels.
void label_size(const std::string& text, int scale, int& w, int& h);

}  // namespace wetcloth::viewer
