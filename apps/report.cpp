// Run reports (see report.hpp).
#include "apps/report.hpp"

#include <sys/resource.h>
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "io/atomic_output_file.hpp"
#include "io/sha256.hpp"
#include "parallel/memory.hpp"

namespace dpts::cli {

double process_cpu_s() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

StageClock::StageClock() : start_(std::chrono::steady_clock::now()) {}

double StageClock::wall_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string StageClock::stage() const {
  std::lock_guard<std::mutex> hold(lock_);
  return marks_.empty() ? std::string() : marks_.back().stage;
}

double StageClock::cpu_s() const { return process_cpu_s(); }

void StageClock::enter(std::string_view stage) {
  std::lock_guard<std::mutex> hold(lock_);
  if (!marks_.empty() && marks_.back().stage == stage) return;
  marks_.push_back({std::string(stage), wall_s(), process_cpu_s()});
}

std::string StageClock::json() const {
  std::lock_guard<std::mutex> hold(lock_);
  io::JsonArray out;
  const double wall_end = wall_s(), cpu_end = process_cpu_s();
  for (std::size_t i = 0; i < marks_.size(); ++i) {
    const double w1 = i + 1 < marks_.size() ? marks_[i + 1].wall : wall_end;
    const double c1 = i + 1 < marks_.size() ? marks_[i + 1].cpu : cpu_end;
    out.raw(io::JsonObject()
                .add("stage", marks_[i].stage)
                .add("wall_s", w1 - marks_[i].wall)
                .add("cpu_s", c1 - marks_[i].cpu)
                .str());
  }
  return out.str();
}

std::string output_options_json(const ParOptions& o) {
  io::JsonObject j;
  j.add("algo", o.algo_text).add("keep", o.keep_text);
  if (o.max_error) j.add("max_error", *o.max_error);
  if (par::is_meta(o.algo))
    j.add("levels", o.levels).add("tile_mb", o.tile_mb).add("value_points", o.value_points);
  if (o.algo == par::Algorithm::qem) j.add("levels", o.levels).add("tile_mb", o.tile_mb);
  j.add("vp_volume", o.elimination.vp_volume == core::VolumeMethod::exact ? "exact" : "mc")
      .add("vp_samples", o.elimination.vp_samples)
      .add("seed", static_cast<unsigned long long>(o.elimination.seed))
      .add("t_srs", o.t_srs)
      .add("band", o.band)
      .add("ascii", o.ascii)
      .add("format", io::extension_of(o.format) + 1);
  io::JsonObject config;
  for (const auto& [k, v] : o.config) config.add(k, v);
  j.raw("config", config.str());
  return j.str();
}

std::string resume_key(const ParOptions& o) {
  std::error_code ec;
  const auto abs = std::filesystem::absolute(o.input, ec).lexically_normal().string();
  struct stat st {};
  const bool ok = ::stat(o.input.c_str(), &st) == 0;
  const long long mtime_ns =
      ok ? static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec : -1;
  const long long size = ok ? static_cast<long long>(st.st_size) : -1;
  return io::sha256_hex(std::string(DPTS_VERSION) + "\n" + abs + "\n" + std::to_string(size) +
                        "\n" + std::to_string(mtime_ns) + "\n" + output_options_json(o));
}

std::string input_json(const io::DemInfo& dem, std::size_t valid_cells,
                       std::size_t surface_vertices) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(dem.path, ec);
  return io::JsonObject()
      .add("path", dem.path)
      .add("bytes", static_cast<unsigned long long>(ec ? 0 : bytes))
      .add("width", dem.width)
      .add("height", dem.height)
      .add("cells", dem.cell_count())
      .add("valid_cells", valid_cells)
      .add("surface_vertices", surface_vertices)
      .add("band", dem.band)
      .add("type", dem.type_name)
      .add("crs", dem.output_crs_name.empty() ? std::string("none") : dem.output_crs_name)
      .raw("notes", [&] {
        io::JsonArray notes;
        for (const std::string& note : dem.notes) notes.add(note);
        return notes.str();
      }())
      .str();
}

std::string output_json(const std::string& path, std::size_t vertices, std::size_t faces,
                        const std::string& file) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(file, ec);
  return io::JsonObject()
      .add("path", path)
      .add("vertices", vertices)
      .add("faces", faces)
      .add("bytes", static_cast<unsigned long long>(ec ? 0 : bytes))
      .add("sha256", io::sha256_file(file))
      .str();
}

std::string pieces_json(const par::MetaStats& stats) {
  io::JsonArray out;
  for (const auto& p : stats.pieces) {
    out.raw(io::JsonObject()
                .add("col0", p.piece.col0)
                .add("row0", p.piece.row0)
                .add("width", p.piece.width)
                .add("height", p.piece.height)
                .add("vertices", p.piece.vertices)
                .add("value", p.value)
                .add("budget", p.budget)
                .add("kept", p.kept)
                .add("read_s", p.read_s)
                .add("simplify_s", p.simplify_s)
                .str());
  }
  return out.str();
}

std::string RunReport::write(const ParOptions& o, const std::string& status, int exit_code,
                             const std::string& error) const {
  if (path.empty()) return {};
  try {
    io::JsonArray command;
    for (const std::string& a : args) command.add(a);
    io::JsonObject j;
    j.add("dpts_version", DPTS_VERSION).add("status", status).add("exit_code", exit_code);
    if (!error.empty()) j.add("error", error);
    j.raw("command", command.str())
        .raw("input", input_json)
        .raw("options", output_options_json(o))
        .add("threads", threads > 0 ? threads : o.threads)
        .raw("output", output_json)
        .raw("stages", clock.json())
        .add("wall_s", clock.wall_s())
        .add("cpu_s", clock.cpu_s())
        .add("peak_rss_mb", static_cast<double>(par::peak_rss_kb()) / 1024.0);
    if (!pieces_json.empty()) j.raw("pieces", pieces_json);
    j.add("resume_key", resume_key(o));
    io::AtomicOutputFile out(path);
    out.stream() << j.str() << "\n";
    out.commit();
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

}  // namespace dpts::cli
