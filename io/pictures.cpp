// Error map and hillshade comparison: a small raster canvas, a 5 x 7 font, GDAL for the
// hillshades (GDALDEMProcessing) and the PNG encoding.
#include "io/pictures.hpp"

#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <gdal_utils.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>

#include "core/errors.hpp"

namespace dpts::io {
namespace {

struct Rgb {
  unsigned char r, g, b;
};

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kNoData{205, 205, 205};   // error map: no value
constexpr Rgb kNoShade{238, 236, 226};  // hillshade: no value

// A 5 x 7 pixel font: each row's 5 bits, the leftmost first. Lower-case letters other than
// m and k (units) are drawn as capitals.
struct Glyph {
  char c;
  std::uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x15, 0x15}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
};

const Glyph* glyph(char c) {
  if (c != 'm' && c != 'k') c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kFont) {
    if (g.c == c) return &g;
  }
  return nullptr;  // a space, or a character the font lacks: left blank
}

constexpr int kTextScale = 2;                // font pixels are 2 x 2 canvas pixels
constexpr int kTextHeight = 7 * kTextScale;  // a line of text
constexpr int kAdvance = 6 * kTextScale;     // a character and its gap

class Canvas {
 public:
  Canvas(int width, int height)
      : w_(width), h_(height), px_(static_cast<std::size_t>(3) * width * height, 255) {}
  int width() const { return w_; }
  int height() const { return h_; }

  void set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    unsigned char* p = &px_[3 * (static_cast<std::size_t>(y) * w_ + x)];
    p[0] = c.r, p[1] = c.g, p[2] = c.b;
  }
  void blend(int x, int y, Rgb c, double alpha) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    unsigned char* p = &px_[3 * (static_cast<std::size_t>(y) * w_ + x)];
    const unsigned char src[3] = {c.r, c.g, c.b};
    for (int k = 0; k < 3; ++k) {
      p[k] = static_cast<unsigned char>(std::lround((1 - alpha) * p[k] + alpha * src[k]));
    }
  }
  void fill(int x0, int y0, int width, int height, Rgb c) {
    for (int y = y0; y < y0 + height; ++y) {
      for (int x = x0; x < x0 + width; ++x) set(x, y, c);
    }
  }
  // A line one pixel wide, each pixel blended once.
  void line(double x0, double y0, double x1, double y1, Rgb c, double alpha) {
    const int steps = static_cast<int>(std::ceil(std::max(std::fabs(x1 - x0), std::fabs(y1 - y0))));
    int px = std::numeric_limits<int>::min(), py = px;
    for (int s = 0; s <= steps; ++s) {
      const double t = steps == 0 ? 0.0 : static_cast<double>(s) / steps;
      const int x = static_cast<int>(std::floor(x0 + t * (x1 - x0)));
      const int y = static_cast<int>(std::floor(y0 + t * (y1 - y0)));
      if (x == px && y == py) continue;
      blend(x, y, c, alpha);
      px = x, py = y;
    }
  }
  // Text with its top left at (x, y).
  void text(int x, int y, const std::string& s, Rgb c) {
    for (const char ch : s) {
      if (const Glyph* g = glyph(ch)) {
        for (int r = 0; r < 7; ++r) {
          for (int b = 0; b < 5; ++b) {
            if (g->rows[r] & (0x10 >> b)) {
              fill(x + b * kTextScale, y + r * kTextScale, kTextScale, kTextScale, c);
            }
          }
        }
      }
      x += kAdvance;
    }
  }
  static int text_width(const std::string& s) {
    return s.empty() ? 0 : static_cast<int>(s.size()) * kAdvance - kTextScale;
  }

  // The canvas as PNG bytes (GDAL's driver, in memory).
  std::string png() const {
    GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
    GDALDriver* png = GetGDALDriverManager()->GetDriverByName("PNG");
    if (mem == nullptr || png == nullptr) throw IoError("GDAL has no PNG driver");
    std::unique_ptr<GDALDataset> ds(mem->Create("", w_, h_, 3, GDT_Byte, nullptr));
    if (!ds || ds->RasterIO(GF_Write, 0, 0, w_, h_, const_cast<unsigned char*>(px_.data()), w_, h_,
                            GDT_Byte, 3, nullptr, 3, static_cast<GSpacing>(3) * w_, 1,
                            nullptr) != CE_None) {
      throw IoError("cannot draw the picture");
    }
    char name[64];
    std::snprintf(name, sizeof name, "/vsimem/dpts-picture-%p.png", static_cast<const void*>(this));
    GDALDataset* out = png->CreateCopy(name, ds.get(), FALSE, nullptr, nullptr, nullptr);
    if (out == nullptr) throw IoError("cannot encode the PNG");
    GDALClose(out);
    vsi_l_offset size = 0;
    GByte* bytes = VSIGetMemFileBuffer(name, &size, TRUE);
    VSIUnlink((std::string(name) + ".aux.xml").c_str());
    if (bytes == nullptr) throw IoError("cannot encode the PNG");
    std::string result(reinterpret_cast<const char*>(bytes), static_cast<std::size_t>(size));
    VSIFree(bytes);
    return result;
  }

 private:
  int w_, h_;
  std::vector<unsigned char> px_;
};

// How a raster maps to a panel: `zoom` panel pixels per cell; at most 1000 pixels on the long
// side, and small rasters enlarged by a whole factor (to about 800).
struct Fit {
  double zoom = 1;
  int w = 1, h = 1;
  // The cells [c0, c1) x [r0, r1) of panel pixel (x, y).
  void block(int x, int y, int width, int height, int& c0, int& c1, int& r0, int& r1) const {
    c0 = std::min(width - 1, static_cast<int>(std::floor(x / zoom)));
    c1 = std::max(c0 + 1, std::min(width, static_cast<int>(std::floor((x + 1) / zoom))));
    r0 = std::min(height - 1, static_cast<int>(std::floor(y / zoom)));
    r1 = std::max(r0 + 1, std::min(height, static_cast<int>(std::floor((y + 1) / zoom))));
  }
};

Fit fit(int width, int height) {
  const int longest = std::max(width, height);
  Fit f;
  if (longest > 1000) {
    f.zoom = 1000.0 / longest;
  } else if (longest < 400) {
    f.zoom = std::floor(800.0 / longest);
  }
  f.w = std::max(1, static_cast<int>(std::floor(width * f.zoom)));
  f.h = std::max(1, static_cast<int>(std::floor(height * f.zoom)));
  return f;
}

// The round number (1, 2, 2.5 or 5 x 10^k) at or above v > 0.
double nice_ceil(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * p >= v * (1 - 1e-12)) return m * p;
  }
  return 10 * p;
}

// The round number (1, 2 or 5 x 10^k) at or below v > 0.
double nice_floor(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * p <= v * (1 + 1e-12)) return m * p;
  }
  return p;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// A scale bar of a round length about a quarter of the panel, with its label, at (x, y).
void scale_bar(Canvas& c, int x, int y, const Fit& f, double cell_m) {
  const double metres_per_pixel = cell_m / f.zoom;
  const double metres = nice_floor(std::max(1e-9, f.w / 4.0 * metres_per_pixel));
  const int length = std::max(1, static_cast<int>(std::lround(metres / metres_per_pixel)));
  c.fill(x, y + 6, length, 3, kBlack);
  c.fill(x, y, 2, 15, kBlack);
  c.fill(x + length - 2, y, 2, 15, kBlack);
  const std::string label = metres >= 1000 ? number(metres / 1000) + " km" : number(metres) + " m";
  c.text(x + length + 10, y + 1, label, kBlack);
}

// ColorBrewer's RdBu, blue for -1, near white for 0, red for +1.
Rgb diverging(double t) {
  static const Rgb stops[] = {{33, 102, 172},  {103, 169, 207}, {209, 229, 240}, {247, 247, 247},
                              {253, 219, 199}, {239, 138, 98},  {178, 24, 43}};
  const double u = (std::clamp(t, -1.0, 1.0) + 1) * 3;  // 0..6
  const int i = std::min(5, static_cast<int>(std::floor(u)));
  const double a = u - i;
  auto mix = [&](unsigned char p, unsigned char q) {
    return static_cast<unsigned char>(std::lround((1 - a) * p + a * q));
  };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g),
          mix(stops[i].b, stops[i + 1].b)};
}

// GDAL's hillshade (azimuth 315, altitude 45, edges computed) of a raster: 1-255, 0 where none.
// A vertical exaggeration for hillshades that shows gentle terrain: the round factor (at least
// 1, at most 50) that steepens the DEM's median slope to about 20 degrees.
double exaggeration(const CellRaster& r) {
  std::vector<float> grades;
  for (int y = 0; y + 1 < r.height; ++y) {
    for (int x = 0; x + 1 < r.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * r.width + x;
      const float z = r.values[i], zx = r.values[i + 1], zy = r.values[i + r.width];
      if (std::isnan(z) || std::isnan(zx) || std::isnan(zy)) continue;
      grades.push_back(
          static_cast<float>(std::hypot((zx - z) / r.cell_x_m, (zy - z) / r.cell_y_m)));
    }
  }
  if (grades.empty()) return 1;
  std::nth_element(grades.begin(), grades.begin() + static_cast<long>(grades.size() / 2),
                   grades.end());
  const double median = grades[grades.size() / 2];
  if (!(median > 0)) return 1;
  return std::clamp(nice_floor(std::tan(20 * M_PI / 180) / median), 1.0, 50.0);
}

std::vector<unsigned char> hillshade(const CellRaster& r, double z_factor) {
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  std::unique_ptr<GDALDataset> src(
      mem == nullptr ? nullptr : mem->Create("", r.width, r.height, 1, GDT_Float32, nullptr));
  if (!src) throw IoError("cannot make the hillshade");
  double gt[6] = {0, r.cell_x_m, 0, 0, 0, -r.cell_y_m};
  src->SetGeoTransform(gt);
  GDALRasterBand* band = src->GetRasterBand(1);
  band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  if (band->RasterIO(GF_Write, 0, 0, r.width, r.height, const_cast<float*>(r.values.data()),
                     r.width, r.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
    throw IoError("cannot make the hillshade");
  }
  const std::string z = number(z_factor);
  const char* args[] = {"-of", "MEM", "-compute_edges", "-z", z.c_str(), nullptr};
  GDALDEMProcessingOptions* options =
      GDALDEMProcessingOptionsNew(const_cast<char**>(args), nullptr);
  int usage_error = 0;
  GDALDatasetH shaded =
      GDALDEMProcessing("", src.get(), "hillshade", nullptr, options, &usage_error);
  GDALDEMProcessingOptionsFree(options);
  if (shaded == nullptr) throw IoError("cannot make the hillshade");
  std::vector<unsigned char> out(r.values.size());
  const CPLErr err = GDALRasterIO(GDALGetRasterBand(shaded, 1), GF_Read, 0, 0, r.width, r.height,
                                  out.data(), r.width, r.height, GDT_Byte, 0, 0);
  GDALClose(shaded);
  if (err != CE_None) throw IoError("cannot make the hillshade");
  return out;
}

// The hillshade drawn into a panel at (x0, y0): each pixel its block's mean shade.
void draw_shade(Canvas& c, int x0, int y0, const Fit& f, const std::vector<unsigned char>& shade,
                int width, int height) {
  for (int y = 0; y < f.h; ++y) {
    for (int x = 0; x < f.w; ++x) {
      int c0, c1, r0, r1;
      f.block(x, y, width, height, c0, c1, r0, r1);
      double sum = 0;
      int n = 0;
      for (int r = r0; r < r1; ++r) {
        for (int col = c0; col < c1; ++col) {
          const unsigned char s = shade[static_cast<std::size_t>(r) * width + col];
          if (s != 0) sum += s, ++n;
        }
      }
      if (n == 0) {
        c.set(x0 + x, y0 + y, kNoShade);
      } else {
        const auto g = static_cast<unsigned char>(std::lround(sum / n));
        c.set(x0 + x, y0 + y, {g, g, g});
      }
    }
  }
}

constexpr int kMargin = 16;
constexpr int kTop = kMargin + kTextHeight + 10;  // below a title line

}  // namespace

std::string error_map_png(const CellRaster& error) {
  GDALAllRegister();  // note: idempotent; the MEM and PNG drivers are needed
  const Fit f = fit(error.width, error.height);
  // The ramp's limit: a round number at or above the 99th percentile of |error|.
  std::vector<float> mags;
  double sq = 0, worst = 0;
  for (const float v : error.values) {
    if (std::isnan(v)) continue;
    mags.push_back(std::fabs(v));
    sq += static_cast<double>(v) * v;
    worst = std::max(worst, static_cast<double>(std::fabs(v)));
  }
  double p99 = 0;
  if (!mags.empty()) {
    const std::size_t k = std::min(mags.size() - 1, static_cast<std::size_t>(0.99 * mags.size()));
    std::nth_element(mags.begin(), mags.begin() + static_cast<long>(k), mags.end());
    p99 = mags[k];
  }
  const double limit = nice_ceil(std::max(p99, 1e-3));
  const double rmse = mags.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(mags.size()));

  const int bar_x = kMargin + f.w + 24, bar_w = 18, bar_h = std::min(f.h, 320);
  const int label_w = Canvas::text_width("-0.000");
  const std::string stats = "RMSE " + number(rmse) + " m, MAX " + number(worst) +
                            " m, COLOURS FULL BEYOND +-" + number(limit) + " m";
  const std::string title = "VERTICAL ERROR: TIN MINUS DEM (m)";
  const int width = std::max({bar_x + bar_w + 8 + label_w + kMargin,
                              kMargin + Canvas::text_width(stats) + kMargin,
                              kMargin + Canvas::text_width(title) + kMargin});
  const int height = kTop + f.h + 14 + 16 + 14 + kTextHeight + kMargin;
  Canvas c(width, height);
  c.text(kMargin, kMargin, title, kBlack);
  for (int y = 0; y < f.h; ++y) {
    for (int x = 0; x < f.w; ++x) {
      int c0, c1, r0, r1;
      f.block(x, y, error.width, error.height, c0, c1, r0, r1);
      float pick = std::numeric_limits<float>::quiet_NaN();
      for (int r = r0; r < r1; ++r) {
        for (int col = c0; col < c1; ++col) {
          const float v = error.values[static_cast<std::size_t>(r) * error.width + col];
          if (!std::isnan(v) && (std::isnan(pick) || std::fabs(v) > std::fabs(pick))) pick = v;
        }
      }
      c.set(kMargin + x, kTop + y, std::isnan(pick) ? kNoData : diverging(pick / limit));
    }
  }
  // The colour bar: +limit at the top, -limit at the bottom, five labelled ticks.
  for (int y = 0; y < bar_h; ++y) {
    const double t = 1 - 2.0 * y / std::max(1, bar_h - 1);
    c.fill(bar_x, kTop + y, bar_w, 1, diverging(t));
  }
  for (int k = 0; k <= 4; ++k) {
    const double t = 1 - 0.5 * k;
    const int y = kTop + static_cast<int>(std::lround((1 - t) / 2 * (bar_h - 1)));
    c.fill(bar_x + bar_w, y, 5, 1, kBlack);
    c.text(bar_x + bar_w + 8, std::clamp(y - kTextHeight / 2, kTop - 4, kTop + bar_h),
           (t > 0 ? "+" : "") + number(t * limit), kBlack);
  }
  scale_bar(c, kMargin, kTop + f.h + 14, f, error.cell_x_m);
  c.text(kMargin, kTop + f.h + 14 + 16 + 14, stats, kBlack);
  return c.png();
}

std::string hillshade_compare_png(const CellRaster& dem, const CellRaster& tin,
                                  const std::string& tin_label,
                                  const std::vector<std::array<double, 4>>& edges) {
  GDALAllRegister();
  const Fit f = fit(dem.width, dem.height);
  const int gap = 16;
  const int width = std::max(kMargin + 2 * f.w + gap + kMargin,
                             kMargin + f.w + gap + Canvas::text_width(tin_label) + kMargin);
  const int height = kTop + f.h + 14 + 16 + kMargin;
  Canvas c(width, height);
  c.text(kMargin, kMargin, "DEM", kBlack);
  const int right = kMargin + f.w + gap;
  c.text(right, kMargin, tin_label, kBlack);
  const double z = exaggeration(dem);
  draw_shade(c, kMargin, kTop, f, hillshade(dem, z), dem.width, dem.height);
  draw_shade(c, right, kTop, f, hillshade(tin, z), tin.width, tin.height);
  // note: edges drawn faint, so that where they crowd the shading still shows.
  const double alpha =
      std::clamp(60.0 * f.w * f.h / std::max<std::size_t>(1, edges.size()) / 400.0, 0.15, 0.8);
  for (const auto& e : edges) {
    c.line(right + (e[0] + 0.5) * f.zoom, kTop + (e[1] + 0.5) * f.zoom,
           right + (e[2] + 0.5) * f.zoom, kTop + (e[3] + 0.5) * f.zoom, {200, 20, 20}, alpha);
  }
  scale_bar(c, kMargin, kTop + f.h + 14, f, dem.cell_x_m);
  if (z > 1) c.text(right, kTop + f.h + 14 + 1, "HEIGHTS x" + number(z) + " FOR SHADING", kBlack);
  return c.png();
}

}  // namespace dpts::io
