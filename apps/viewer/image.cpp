#include "image.hpp"

#include <algorithm>
#include <cstring>

#include "wetcloth/output.hpp"

// Static copies: no clash with the stb symbols libstb.so exports for ImGui.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_easy_font.h>
#include <stb/stb_image_write.h>

namespace wetcloth::viewer {

bool write_png(const std::filesystem::path& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0) return false;
  std::string png;
  auto append = [](void* ctx, void* data, int size) {
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), size);
  };
  if (!stbi_write_png_to_func(append, &png, img.width, img.height, 3, img.rgb.data(),
                              img.width * 3))
    return false;
  try {
    write_file_atomic(path, png);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

void blit(Image& dst, const Image& src, int x, int y) {
  for (int r = 0; r < src.height; ++r) {
    const int dy = y + r;
    if (dy < 0 || dy >= dst.height) continue;
    const int x0 = std::max(0, x), x1 = std::min(dst.width, x + src.width);
    if (x0 >= x1) continue;
    std::memcpy(dst.pixel(x0, dy),
                &src.rgb[(static_cast<std::size_t>(r) * src.width + (x0 - x)) * 3],
                static_cast<std::size_t>(x1 - x0) * 3);
  }
}

void fill_rect(Image& img, int x0, int y0, int x1, int y1, const std::uint8_t c[3], float a) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, img.width), y1 = std::min(y1, img.height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      std::uint8_t* p = img.pixel(x, y);
      for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>(p[k] + a * (c[k] - p[k]) + 0.5f);
    }
}

namespace {

// stb_easy_font knows printable ASCII only; the sweep's labels may hold ω.
std::vector<char> to_ascii(const std::string& text) {
  std::string ascii;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == 0xCF && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) == 0x89) {
      ascii += 'w', ++i;  // ω
    } else if (c >= 0x80) {
      if ((c & 0xC0) != 0x80) ascii += '?';  // one '?' per UTF-8 character
    } else {
      ascii += (c >= 32 && c < 127) || c == '\n' ? static_cast<char>(c) : '?';
    }
  }
  std::vector<char> buf(ascii.begin(), ascii.end());
  buf.push_back('\0');
  return buf;
}

}  // namespace

void label_size(const std::string& text, int scale, int& w, int& h) {
  std::vector<char> buf = to_ascii(text);
  w = stb_easy_font_width(buf.data()) * scale + 4 * scale;
  h = stb_easy_font_height(buf.data()) * scale + 4 * scale;
}

void draw_label(Image& img, int x, int y, const std::string& text, int scale) {
  std::vector<char> buf = to_ascii(text);
  const int pad = 2 * scale;
  const std::uint8_t black[3] = {0, 0, 0}, white[3] = {255, 255, 255};
  fill_rect(img, x, y, x + stb_easy_font_width(buf.data()) * scale + 2 * pad,
            y + stb_easy_font_height(buf.data()) * scale + 2 * pad, black, 0.55f);

  std::vector<char> quads(64 * 1024);
  unsigned char color[4] = {255, 255, 255, 255};
  const int n =
      stb_easy_font_print(0, 0, buf.data(), color, quads.data(), static_cast<int>(quads.size()));
  struct Vertex {
    float x, y, z;
    unsigned char c[4];
  };
  const auto* v = reinterpret_cast<const Vertex*>(quads.data());
  for (int q = 0; q < n; ++q) {
    // Each quad is an axis-aligned rectangle: corners 0 and 2 are opposite.
    const Vertex &a = v[4 * q], &b = v[4 * q + 2];
    fill_rect(img, x + pad + static_cast<int>(a.x * scale), y + pad + static_cast<int>(a.y * scale),
              x + pad + static_cast<int>(b.x * scale), y + pad + static_cast<int>(b.y * scale),
              white, 1.0f);
  }
}

}  // namespace wetcloth::viewer
