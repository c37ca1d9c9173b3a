// The error map and the hillshade comparison: PNGs whose pixels say what the rasters hold.
#include "io/pictures.hpp"

#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <memory>

using namespace dpts;

namespace {

// A decoded PNG: width, height and RGB bytes.
struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  std::array<int, 3> at(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * w + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

Image decode(const std::string& png) {
  GDALAllRegister();
  REQUIRE(png.rfind("\x89PNG\r\n\x1a\n", 0) == 0);
  const std::string name = "/vsimem/pictures_test.png";
  VSIFCloseL(VSIFileFromMemBuffer(
      name.c_str(), reinterpret_cast<GByte*>(const_cast<char*>(png.data())), png.size(), FALSE));
  auto* ds = static_cast<GDALDataset*>(GDALOpen(name.c_str(), GA_ReadOnly));
  REQUIRE(ds != nullptr);
  Image im;
  im.w = ds->GetRasterXSize();
  im.h = ds->GetRasterYSize();
  REQUIRE(ds->GetRasterCount() == 3);
  im.rgb.resize(static_cast<std::size_t>(3) * im.w * im.h);
  REQUIRE(ds->RasterIO(GF_Read, 0, 0, im.w, im.h, im.rgb.data(), im.w, im.h, GDT_Byte, 3, nullptr,
                       3, static_cast<GSpacing>(3) * im.w, 1, nullptr) == CE_None);
  GDALClose(ds);
  VSIUnlink(name.c_str());
  return im;
}

// A 100 x 50 raster of 10 m cells: 0 on the left half, +2 on the right, none in the top row.
io::CellRaster halves() {
  io::CellRaster r;
  r.width = 100;
  r.height = 50;
  r.cell_x_m = r.cell_y_m = 10;
  r.values.assign(5000, 0.0f);
  for (int y = 0; y < 50; ++y) {
    for (int x = 0; x < 100; ++x) {
      float& v = r.values[static_cast<std::size_t>(y) * 100 + x];
      if (y == 0) {
        v = std::numeric_limits<float>::quiet_NaN();
      } else if (x >= 50) {
        v = 2.0f;
      }
    }
  }
  return r;
}

}  // namespace

TEST_CASE("the error map colours each cell by its error, grey where there is none",
          "[io][pictures]") {
  const Image im = decode(io::error_map_png(halves()));
  // 100 x 50 cells, under 400 a side: enlarged 8 x to 800 x 400 pixels, at (16, 40).
  const int x0 = 16, y0 = 16 + 14 + 10, zoom = 8;
  CHECK(im.w > x0 + 100 * zoom);
  CHECK(im.h > y0 + 50 * zoom);
  // Row 0 has no value: grey. Left: 0 (the ramp's middle, near white). Right: +2, the 99th
  // percentile and so the limit: full red.
  CHECK(im.at(x0 + 5, y0 + 3) == std::array<int, 3>{205, 205, 205});
  CHECK(im.at(x0 + 20 * zoom, y0 + 20 * zoom) == std::array<int, 3>{247, 247, 247});
  CHECK(im.at(x0 + 80 * zoom, y0 + 20 * zoom) == std::array<int, 3>{178, 24, 43});
  // The colour bar right of the map: red at the top (+limit), blue at the bottom.
  const int bar = x0 + 100 * zoom + 24 + 9;
  CHECK(im.at(bar, y0) == std::array<int, 3>{178, 24, 43});
  CHECK(im.at(bar, y0 + 319) == std::array<int, 3>{33, 102, 172});
  // Below the map: the scale bar (black) starts at the left margin.
  CHECK(im.at(x0, y0 + 50 * zoom + 14 + 7) == std::array<int, 3>{0, 0, 0});
}

TEST_CASE("a large error map is shrunk and keeps each block's largest error", "[io][pictures]") {
  io::CellRaster r;
  r.width = 3000;
  r.height = 1500;
  r.values.assign(static_cast<std::size_t>(3000) * 1500, 0.25f);
  r.values[static_cast<std::size_t>(750) * 3000 + 1501] = -50.0f;  // one spike
  const Image im = decode(io::error_map_png(r));
  // 1000 pixels wide: 3 cells a pixel. The limit is 0.25 (the 99th percentile): the spike's
  // pixel is full blue, its neighbours full red.
  const int x0 = 16, y0 = 40;
  CHECK(im.at(x0 + 1501 / 3, y0 + 750 / 3) == std::array<int, 3>{33, 102, 172});
  CHECK(im.at(x0 + 1501 / 3 + 1, y0 + 750 / 3) == std::array<int, 3>{178, 24, 43});
  CHECK(im.at(x0 + 1501 / 3, y0 + 750 / 3 + 1) == std::array<int, 3>{178, 24, 43});
}

TEST_CASE("the hillshade comparison shades both surfaces alike and draws the edges asked for",
          "[io][pictures]") {
  io::CellRaster dem;
  dem.width = 60;
  dem.height = 40;
  dem.cell_x_m = dem.cell_y_m = 10;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 60; ++x) {
      dem.values.push_back(static_cast<float>(100 + 30 * std::sin(x * 0.2) * std::cos(y * 0.25)));
    }
  }
  const io::CellRaster same = dem;
  // Same surface: the two panels have the same pixels. 60 x 40 cells: 13 x zoom, 780 x 520.
  const Image im = decode(io::hillshade_compare_png(dem, same, "TIN", {}));
  const int zoom = 13, w = 60 * zoom, x0 = 16, right = 16 + w + 16, y0 = 40;
  REQUIRE(im.w >= right + w);
  int differing = 0, shades = 0;
  for (int y = 0; y < 40 * zoom; y += 7) {
    for (int x = 0; x < w; x += 7) {
      differing += im.at(x0 + x, y0 + y) != im.at(right + x, y0 + y);
      shades += im.at(x0 + x, y0 + y)[0] != im.at(x0, y0)[0];
    }
  }
  CHECK(differing == 0);
  CHECK(shades > 100);  // the hills are shaded, not one flat grey
  // An edge from cell (5, 5) to cell (50, 5): red pixels along row 5's centre on the right.
  const Image with = decode(io::hillshade_compare_png(dem, same, "TIN", {{5, 5, 50, 5}}));
  const int row = y0 + static_cast<int>(5.5 * zoom);
  const auto px = with.at(right + 20 * zoom, row);
  CHECK(px[0] > px[1] + 40);
  CHECK(with.at(x0 + 20 * zoom, row) == im.at(x0 + 20 * zoom, row));  // the DEM's panel: none
}
