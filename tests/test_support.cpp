// Helpers shared by the tests.
#include "test_support.hpp"

#include <fcntl.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"

namespace dpts::test {

core::HeightGrid make_grid(int width, int height, const std::function<double(int, int)>& f) {
  core::HeightGrid g;
  g.width = width;
  g.height = height;
  g.z.resize(static_cast<std::size_t>(width) * height);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) g.z[g.index(c, r)] = f(c, r);
  }
  return g;
}

core::HeightGrid random_voids_grid(std::uint32_t seed, int trial,
                                   const std::function<double(int, int)>& f) {
  std::uint32_t state = seed * 2654435761u + static_cast<std::uint32_t>(trial) * 40503u;
  auto next = [&] { return state = state * 1664525u + 1013904223u; };
  const int w = 1 + static_cast<int>(next() >> 29), h = 1 + static_cast<int>(next() >> 29);
  const std::uint32_t voids = next() >> 30;
  std::vector<char> hole(static_cast<std::size_t>(w) * h);
  for (auto& x : hole) x = (next() >> 30) < voids;
  return make_grid(w, h, [&](int c, int r) {
    return hole[static_cast<std::size_t>(r) * w + c] ? std::numeric_limits<double>::quiet_NaN()
                                                     : f(c, r);
  });
}

namespace {
const double kVoid = std::numeric_limits<double>::quiet_NaN();
}  // namespace

core::HeightGrid hills_with_voids(int w, int h) {
  return make_grid(w, h, [w, h](int c, int r) {
    if (std::hypot(c - w / 2.0, r - h / 2.0) < 7.0) return kVoid;
    if (r == h / 4 && c >= 6 && c < w - 20) return kVoid;
    if (c >= w - 6 && r >= h / 2 + 10 && r <= h / 2 + 14) return kVoid;
    if (c + r < 3) return kVoid;
    return 100.0 + 20.0 * std::sin(c * 0.3) * std::cos(r * 0.25) + 0.5 * c + 0.01 * r * r;
  });
}

core::TriMesh pyramid_mesh(int n, double radius, double height) {
  const double pi = std::acos(-1.0);
  core::TriMesh m;
  m.xyz = {0, 0, height};
  for (int i = 0; i < n; ++i) {
    m.xyz.insert(m.xyz.end(),
                 {radius * std::cos(2 * pi * i / n), radius * std::sin(2 * pi * i / n), 0});
  }
  const auto sides = static_cast<std::uint32_t>(n);
  for (std::uint32_t i = 0; i < sides; ++i) m.faces.push_back({0, 1 + i, 1 + (i + 1) % sides});
  return m;
}

core::TriMesh hills_mesh(int w, int h, std::vector<std::uint32_t>* opposites) {
  const auto g = make_grid(w, h, [w, h](int c, int r) {
    if (std::hypot(c - 12.0, r - 14.0) < 4.0) return kVoid;
    if (c >= w - 6 && r >= h / 2 - 2 && r <= h / 2 + 2) return kVoid;
    if (c + r < 3) return kVoid;
    return 10.0 * std::sin(c * 0.3) * std::cos(r * 0.25) + 0.3 * c;
  });
  const core::Tin tin = core::grid_tin(g, core::Diagonal::nw_se, opposites);
  core::TriMesh m;
  for (std::uint32_t cell : tin.cells) {
    const double c = cell % static_cast<std::uint32_t>(w), r = cell / static_cast<std::uint32_t>(w);
    m.xyz.insert(m.xyz.end(), {c, -r, g.z[cell]});
  }
  m.faces = tin.faces;
  core::fix_orientation(m, opposites);
  return m;
}

std::set<std::pair<double, double>> border_points(const core::TriMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& f : m.faces) {
    for (int i = 0; i < 3; ++i) {
      const auto a = f[i], b = f[(i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::set<std::pair<double, double>> out;
  for (const auto& [e, n] : uses) {
    if (n != 1) continue;
    for (auto v : {e.first, e.second}) out.insert({m.xyz[3 * v], m.xyz[3 * v + 1]});
  }
  return out;
}

TempDir::TempDir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "dpts-test-XXXXXX").string();
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
  path_ = buf.data();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::permissions(path_, std::filesystem::perms::owner_all,
                               std::filesystem::perm_options::add, ec);
  std::filesystem::remove_all(path_, ec);
}

std::vector<std::string> TempDir::files() const {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(path_)) {
    names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunResult run(const std::string& exe, const std::vector<std::string>& args,
              const RunOptions& options) {
  TempDir io;
  const auto out_path = io / "stdout", err_path = io / "stderr";
  // The child's environment, made before the fork.
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    bool replaced = false;
    for (const auto& [name, value] : options.env) replaced |= entry.rfind(name + "=", 0) == 0;
    if (!replaced) env_strings.push_back(entry);
  }
  for (const auto& [name, value] : options.env) env_strings.push_back(name + "=" + value);
  std::vector<char*> envp;
  for (auto& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // note: the child calls only async-signal-safe functions (no allocation) until execve: a
  // test may fork beside other threads (TBB's workers, a reader), whose locks it would inherit.
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int out = options.stdout_to.empty()
                        ? ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600)
                        : ::open(options.stdout_to.c_str(), O_WRONLY);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    const int in =
        ::open(options.stdin_from.empty() ? "/dev/null" : options.stdin_from.c_str(), O_RDONLY);
    ::dup2(in, 0);
    ::dup2(out, 1);
    ::dup2(err, 2);
    if (options.close_stderr) ::close(2);
    if (options.close_stdout) ::close(1);
    if (options.file_size_limit > 0) {
      ::signal(SIGXFSZ, SIG_IGN);  // kept across exec: writes fail with EFBIG instead
      const rlimit limit{options.file_size_limit, options.file_size_limit};
      ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    if (options.address_space_limit > 0) {
      const rlimit limit{options.address_space_limit, options.address_space_limit};
      ::setrlimit(RLIMIT_AS, &limit);
    }
    if (options.cpu_limit_s > 0) {
      const rlimit no_core{0, 0};
      ::setrlimit(RLIMIT_CORE, &no_core);
      const rlimit limit{static_cast<rlim_t>(options.cpu_limit_s), RLIM_INFINITY};
      ::setrlimit(RLIMIT_CPU, &limit);
    }
    if (!options.cwd.empty() && ::chdir(options.cwd.c_str()) != 0) ::_exit(126);
    ::execve(exe.c_str(), argv.data(), envp.data());
    ::_exit(127);
  }
  int status = 0;
  // note: one loop for every child: polled, with sleeps from 0.5 ms growing to 10 ms (a quick
  // child is not slowed), sending the signal when asked and killing the child past the wall
  // limit (an interrupted run that does not stop included).
  RunResult r;
  const auto start = std::chrono::steady_clock::now();
  auto sent_at = start;
  bool sent = false;
  auto nap = std::chrono::microseconds(500);
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (t > options.wall_limit_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      std::string command = exe;
      for (const auto& a : args) command += " " + a;
      std::cerr << "test::run: " << command << ": still running after " << options.wall_limit_s
                << " s, killed; its stderr:\n"
                << file_bytes(err_path) << "\n";
      break;
    }
    if (!sent && ((!options.signal_when.empty() &&
                   file_bytes(err_path).find(options.signal_when) != std::string::npos) ||
                  (options.signal_after_s > 0 && t >= options.signal_after_s))) {
      ::kill(pid, options.signal);
      sent = true;
      sent_at = std::chrono::steady_clock::now();
    }
    std::this_thread::sleep_for(nap);
    nap = std::min(nap * 2, std::chrono::microseconds(10000));
  }
  if (sent) {
    r.seconds_after_signal =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - sent_at).count();
  }
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = file_bytes(out_path);
  r.err = file_bytes(err_path);
  // A child that crashed or aborted (a sanitizer's report, std::terminate) says why on its
  // stderr, which the tests do not print: shown here so that a CI log holds it.
  const int sig = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  if (sig == SIGABRT || sig == SIGSEGV || sig == SIGBUS || sig == SIGILL || sig == SIGFPE ||
      r.exit_code == 128 + SIGABRT) {
    std::cerr << "test::run: " << exe << " died (exit " << r.exit_code << "); its stderr:\n"
              << r.err.substr(r.err.size() > 20000 ? r.err.size() - 20000 : 0) << "\n";
  }
  return r;
}

void write_geotiff(const std::filesystem::path& path, const core::HeightGrid& grid,
                   const std::vector<double>& geotransform, const std::string& wkt, double nodata) {
  GDALAllRegister();
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = drv->Create(path.c_str(), grid.width, grid.height, 1, GDT_Float32, nullptr);
  if (!ds) throw std::runtime_error("cannot create " + path.string());
  std::vector<double> gt = geotransform;
  ds->SetGeoTransform(gt.data());
  if (!wkt.empty()) ds->SetProjection(wkt.c_str());
  GDALRasterBand* band = ds->GetRasterBand(1);
  band->SetNoDataValue(nodata);
  std::vector<float> values(grid.z.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    values[i] = std::isnan(grid.z[i]) ? static_cast<float>(nodata) : static_cast<float>(grid.z[i]);
  }
  if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, values.data(), grid.width,
                     grid.height, GDT_Float32, 0, 0) != CE_None) {
    throw std::runtime_error("cannot write " + path.string());
  }
  GDALClose(ds);
}

void write_raster(const std::filesystem::path& path, const core::HeightGrid& grid,
                  const RasterSpec& spec) {
  GDALAllRegister();
  const GDALDataType type = GDALGetDataTypeByName(spec.type.c_str());
  if (type == GDT_Unknown) throw std::runtime_error("unknown GDAL type " + spec.type);
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* format = GetGDALDriverManager()->GetDriverByName(spec.driver.c_str());
  if (!format) throw std::runtime_error("no GDAL driver " + spec.driver);
  std::vector<const char*> opts;
  for (const auto& o : spec.creation_options) opts.push_back(o.c_str());
  opts.push_back(nullptr);
  GDALDataset* ds = mem->Create("", grid.width, grid.height, spec.bands, type, nullptr);
  if (!ds) throw std::runtime_error("cannot create a MEM raster of " + spec.type);
  std::vector<double> gt = spec.geotransform;
  ds->SetGeoTransform(gt.data());
  if (!spec.wkt.empty()) ds->SetProjection(spec.wkt.c_str());
  const bool signed_byte =
      type == GDT_Byte && std::find(spec.creation_options.begin(), spec.creation_options.end(),
                                    "PIXELTYPE=SIGNEDBYTE") != spec.creation_options.end();
  for (int b = 1; b <= spec.bands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    if (spec.has_nodata && type == GDT_Int64) {
      band->SetNoDataValueAsInt64(static_cast<std::int64_t>(spec.nodata));
    } else if (spec.has_nodata && type == GDT_UInt64) {
      band->SetNoDataValueAsUInt64(static_cast<std::uint64_t>(spec.nodata));
    } else if (spec.has_nodata) {
      band->SetNoDataValue(spec.nodata);
    }
    if (spec.scale != 1.0) band->SetScale(spec.scale);
    if (spec.offset != 0.0) band->SetOffset(spec.offset);
    std::vector<double> values(grid.z.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      const double z = grid.z[i];
      values[i] = std::isnan(z) && spec.has_nodata ? spec.nodata : z + 1000.0 * (b - 1);
      if (signed_byte && values[i] < 0) values[i] += 256;  // stored as two's complement
    }
    if (band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, values.data(), grid.width,
                       grid.height, GDT_Float64, 0, 0) != CE_None) {
      throw std::runtime_error("cannot write band " + std::to_string(b));
    }
  }
  GDALDataset* out = format->CreateCopy(path.c_str(), ds, FALSE, const_cast<char**>(opts.data()),
                                        nullptr, nullptr);
  GDALClose(ds);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  GDALClose(out);
}

std::string epsg_wkt(int code) {
  OGRSpatialReference srs;
  srs.importFromEPSG(code);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string out = wkt;
  CPLFree(wkt);
  return out;
}

std::vector<double> grid_xy(const core::HeightGrid& grid, const core::Tin& tin) {
  std::vector<double> xy;
  for (std::uint32_t cell : tin.cells) {
    xy.push_back(cell % grid.width);
    xy.push_back(cell / grid.width);
  }
  return xy;
}

std::string shared_data(const std::string& name) {
  return std::string(DPTS_SHARED_DATA_DIR) + "/" + name;
}

// Frame positions of a TIN's vertices.
std::vector<double> frame_xy(const core::HeightGrid& g, const core::GridFrame& f,
                             const core::Tin& tin) {
  std::vector<double> xy;
  for (std::uint32_t cell : tin.cells) {
    const int c = static_cast<int>(cell % g.width), r = static_cast<int>(cell / g.width);
    xy.push_back(f.u(c, r));
    xy.push_back(f.w(c, r));
  }
  return xy;
}

// Number of interior edges whose opposite vertex lies strictly inside the circumcircle.
std::size_t non_delaunay_edges(const std::vector<double>& xy, const core::Tin& tin) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>
      apex_of;  // directed edge -> apex
  for (const auto& f : tin.faces) {
    for (int i = 0; i < 3; ++i) apex_of[{f[i], f[(i + 1) % 3]}] = f[(i + 2) % 3];
  }
  std::size_t bad = 0;
  for (const auto& [edge, apex] : apex_of) {
    const auto twin = apex_of.find({edge.second, edge.first});
    if (twin == apex_of.end()) continue;
    auto P = [&](std::uint32_t v) { return std::pair<double, double>{xy[2 * v], xy[2 * v + 1]}; };
    const auto [ax, ay] = P(edge.first);
    const auto [bx, by] = P(edge.second);
    const auto [cx, cy] = P(apex);
    const auto [dx, dy] = P(twin->second);
    // In-circle determinant of d against ccw triangle (a, b, c).
    const double adx = ax - dx, ady = ay - dy, bdx = bx - dx, bdy = by - dy, cdx = cx - dx,
                 cdy = cy - dy;
    const double det = (adx * adx + ady * ady) * (bdx * cdy - bdy * cdx) -
                       (bdx * bdx + bdy * bdy) * (adx * cdy - ady * cdx) +
                       (cdx * cdx + cdy * cdy) * (adx * bdy - ady * bdx);
    if (det > 1e-9) ++bad;
  }
  return bad;
}

// Checks every structural property of a simplified TIN over grid g.
void check_tin(const core::HeightGrid& g, const core::Tin& tin, const core::GridFrame& f) {
  const auto xy = frame_xy(g, f, tin);
  const core::MeshCheck mc = core::check_mesh(xy, tin.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  const double det = std::fabs(f.m[0][0] * f.m[1][1] - f.m[0][1] * f.m[1][0]);
  CHECK(mc.area == Approx(core::footprint_area_cells(g) * det).epsilon(1e-12));
  CHECK(core::faces_over_nodata(g, grid_xy(g, tin), tin.faces) == 0);
  CHECK(non_delaunay_edges(xy, tin) == 0);
  CHECK(std::is_sorted(tin.cells.begin(), tin.cells.end()));
  // Every kept vertex is used by a face.
  std::vector<bool> used(tin.cells.size(), false);
  for (const auto& face : tin.faces) {
    for (auto v : face) used[v] = true;
  }
  CHECK(std::count(used.begin(), used.end(), false) == 0);
}

}  // namespace dpts::test
