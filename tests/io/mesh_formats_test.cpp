// OBJ, STL and GeoPackage outputs: bytes and values against a hand-made mesh.
#include "io/mesh_formats.hpp"

#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

#include "core/errors.hpp"
#include "io/atomic_output_file.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

// Two faces over the unit square, lifted: (0,0,1) (1,0,2) (1,1,3) (0,1,4); counter-clockwise.
io::Mesh square() {
  io::Mesh m;
  m.xyz = {0, 0, 1, 1, 0, 2, 1, 1, 3, 0, 1, 4};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  m.comments = {"made by hand", "crs none"};
  return m;
}

std::string write(const test::TempDir& dir, const std::string& name, const io::Mesh& mesh,
                  const io::MeshWriteOptions& o, double* moved = nullptr) {
  const auto path = dir / name;
  io::AtomicOutputFile out(path);
  const double m = io::write_mesh(out, mesh, o);
  if (moved) *moved = m;
  out.commit();
  return path.string();
}

float float_at(const std::string& bytes, std::size_t offset) {
  float v = 0;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

}  // namespace

TEST_CASE("the output format comes from --format, else the extension, else PLY", "[io]") {
  CHECK(io::mesh_format_of("a/b.OBJ") == io::MeshFormat::obj);
  CHECK(io::mesh_format_of("b.stl") == io::MeshFormat::stl);
  CHECK(io::mesh_format_of("b.gpkg") == io::MeshFormat::gpkg);
  CHECK(io::mesh_format_of("b.ply") == io::MeshFormat::ply);
  CHECK(io::mesh_format_of("b.mesh") == io::MeshFormat::ply);
  CHECK(io::mesh_format_of("/dev/stdout") == io::MeshFormat::ply);
  CHECK(io::parse_mesh_format("GPKG") == io::MeshFormat::gpkg);
  CHECK_FALSE(io::parse_mesh_format("las").has_value());
  CHECK(std::string(io::extension_of(io::MeshFormat::stl)) == ".stl");
}

TEST_CASE("OBJ: comments, vertices as round-trip numbers, 1-based faces", "[io]") {
  test::TempDir dir;
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::obj;
  io::Mesh m = square();
  m.xyz[0] = 0.1;  // shortest round-trip text
  const auto path = write(dir, "m.obj", m, o);
  CHECK(test::file_bytes(path) ==
        "# made by hand\n# crs none\n"
        "v 0.1 0 1\nv 1 0 2\nv 1 1 3\nv 0 1 4\n"
        "f 1 2 3\nf 1 3 4\n");
}

TEST_CASE("binary STL: header, count, unit normals, float32 corners", "[io]") {
  test::TempDir dir;
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::stl;
  double moved = -1;
  const auto bytes = test::file_bytes(write(dir, "m.stl", square(), o, &moved));
  REQUIRE(bytes.size() == 84 + 2 * 50);
  CHECK(bytes.rfind("solid", 0) != 0);  // readers take a header starting so for ASCII
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);
  CHECK(count == 2);
  // Face 0: (0,0,1) (1,0,2) (1,1,3): normal (1,0,0) x (1,1,2) = (-1,-1,1) / sqrt 3.
  const float r = static_cast<float>(1 / std::sqrt(3.0));
  CHECK(float_at(bytes, 84) == Approx(-r));
  CHECK(float_at(bytes, 88) == Approx(-r));
  CHECK(float_at(bytes, 92) == Approx(r));
  const float corners[] = {0, 0, 1, 1, 0, 2, 1, 1, 3};
  for (int k = 0; k < 9; ++k) CHECK(float_at(bytes, 96 + 4 * k) == corners[k]);
  CHECK(bytes.substr(132, 2) == std::string(2, '\0'));
  CHECK(moved == 0);  // small integers are exact in float32

  // UTM-sized coordinates do not fit float32: how far they moved is returned.
  io::Mesh far = square();
  far.xyz[1] = 9110816.4;
  write(dir, "far.stl", far, o, &moved);
  CHECK(moved == Approx(0.4).margin(1e-6));
}

TEST_CASE("ASCII STL keeps doubles exactly", "[io]") {
  test::TempDir dir;
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::stl;
  o.ascii = true;
  io::Mesh m = square();
  m.faces.resize(1);
  m.xyz[1] = 9110816.4;
  const auto text = test::file_bytes(write(dir, "m.stl", m, o));
  CHECK(text.rfind("solid dpts\nfacet normal ", 0) == 0);
  CHECK(text.find("vertex 0 9110816.4 1\nvertex 1 0 2\nvertex 1 1 3\nendloop\nendfacet\n") !=
        std::string::npos);
  CHECK(text.size() >= 14);
  CHECK(text.substr(text.size() - 14) == "endsolid dpts\n");
}

TEST_CASE("GeoPackage: one Polygon Z layer, a feature per face, with the CRS", "[io]") {
  GDALAllRegister();
  test::TempDir dir;
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::gpkg;
  o.crs_wkt = test::epsg_wkt(32611);
  o.layer = "terrain";
  const auto path = write(dir, "m.gpkg", square(), o);
  CHECK(dir.files() == std::vector<std::string>{"m.gpkg"});  // no temporary or journal left
  auto* ds = static_cast<GDALDataset*>(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  REQUIRE(ds != nullptr);
  REQUIRE(ds->GetLayerCount() == 1);
  OGRLayer* layer = ds->GetLayer(0);
  CHECK(std::string(layer->GetName()) == "terrain");
  CHECK(layer->GetGeomType() == wkbPolygon25D);
  CHECK(layer->GetFeatureCount() == 2);
  REQUIRE(layer->GetSpatialRef() != nullptr);
  CHECK(std::string(layer->GetSpatialRef()->GetAuthorityCode(nullptr)) == "32611");
  OGRFeature* f = layer->GetNextFeature();
  REQUIRE(f != nullptr);
  char* wkt = nullptr;
  f->GetGeometryRef()->exportToWkt(&wkt, wkbVariantIso);
  CHECK(std::string(wkt) == "POLYGON Z ((0 0 1,1 0 2,1 1 3,0 0 1))");
  CPLFree(wkt);
  OGRFeature::DestroyFeature(f);
  GDALClose(ds);
}

TEST_CASE("a GeoPackage is the same bytes each time, and a long name fits", "[io]") {
  GDALAllRegister();
  test::TempDir one, two;
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::gpkg;
  o.crs_wkt = test::epsg_wkt(32611);
  const auto first = test::file_bytes(write(one, "m.gpkg", square(), o));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // GDAL's clock has ms
  CHECK(test::file_bytes(write(two, "m.gpkg", square(), o)) == first);
  // SQLite's journal beside the temporary file must fit NAME_MAX (255) too.
  const std::string name = std::string(250, 'g') + ".gpkg";
  write(one, name, square(), o);
  CHECK(std::filesystem::file_size(one.path() / name) > 0);
}

TEST_CASE("a GeoPackage refuses a stream output", "[io]") {
  io::AtomicOutputFile out("/dev/null");
  io::MeshWriteOptions o;
  o.format = io::MeshFormat::gpkg;
  CHECK_THROWS_AS(io::write_mesh(out, square(), o), UsageError);
}
