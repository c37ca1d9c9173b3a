// The sample-point CSV reader and the per-pair CSV writer, strict and locale-free.
#include "io/sample_points.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <string_view>

#include "core/errors.hpp"
#include "io/input_file.hpp"

namespace dpts::io {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// What a message shows of a field or line: at most 40 characters.
std::string shown(std::string_view s) {
  return "'" + std::string(s.substr(0, 40)) + (s.size() > 40 ? "...'" : "'");
}

void append_number(std::string& out, double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, res.ptr);
}

}  // namespace

SampleSets read_sample_points(std::istream& in, const std::string& name) {
  auto fail = [&](std::size_t line, const std::string& what) -> void {
    throw InputError(name + ": line " + std::to_string(line) + ": " + what);
  };
  std::string text;
  std::size_t line = 1;
  if (!std::getline(in, text)) fail(1, "expected the header set,x,y, found an empty file");
  if (!text.empty() && text.back() == '\r') text.pop_back();
  if (text != "set,x,y") fail(1, "expected the header set,x,y, found " + shown(text));
  // Rows as read: (set, x, y, line).
  struct Row {
    std::uint64_t set;
    double x, y;
    std::size_t line;
  };
  std::vector<Row> rows;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::string_view fields[3];
    std::string_view rest = text;
    int n = 0;
    for (;; ++n) {
      const auto comma = rest.find(',');
      if (n < 3) fields[n] = trim(rest.substr(0, comma));
      if (comma == std::string_view::npos) break;
      rest.remove_prefix(comma + 1);
    }
    if (n + 1 != 3) {
      fail(line, "expected 3 values set,x,y, found " + std::to_string(n + 1) +
                     (text.empty() ? " (an empty line)" : ""));
    }
    Row r{0, 0, 0, line};
    const auto set_end = fields[0].data() + fields[0].size();
    const auto set_res = std::from_chars(fields[0].data(), set_end, r.set);
    if (fields[0].empty() || set_res.ec != std::errc() || set_res.ptr != set_end) {
      fail(line, "set " + shown(fields[0]) + ": expected an integer >= 0");
    }
    for (int k = 1; k <= 2; ++k) {
      double& v = k == 1 ? r.x : r.y;
      const auto end = fields[k].data() + fields[k].size();
      const auto res = std::from_chars(fields[k].data(), end, v);
      if (fields[k].empty() || res.ec != std::errc() || res.ptr != end || !std::isfinite(v)) {
        fail(line, std::string(k == 1 ? "x " : "y ") + shown(fields[k]) +
                       ": expected a finite number");
      }
    }
    rows.push_back(r);
  }
  if (in.bad()) throw InputError(name + ": read failed");
  if (rows.empty()) fail(line, "no points after the header (expected lines set,x,y)");
  // Sets 0 to S-1: count each set's points (a map: set numbers come from the file, so no
  // allocation follows them), then look for a gap.
  std::map<std::uint64_t, std::size_t> count, first_line;
  for (const Row& r : rows) {
    ++count[r.set];
    first_line.emplace(r.set, r.line);
  }
  std::uint64_t expected = 0;
  for (const auto& [set, n] : count) {
    if (set != expected) {
      fail(first_line[set], "set " + std::to_string(set) + ", but set " +
                                std::to_string(expected) +
                                " has no points (sets are numbered from 0 without gaps)");
    }
    ++expected;
  }
  for (const auto& [set, n] : count) {
    if (n < 2) {
      fail(first_line[set], "set " + std::to_string(set) +
                                " has only this point (each set needs at least 2)");
    }
    if (n != count.begin()->second) {
      fail(first_line[set], "set " + std::to_string(set) + " has " + std::to_string(n) +
                                " points where set 0 has " + std::to_string(count.begin()->second) +
                                " (every set needs the same number)");
    }
  }
  SampleSets sets(count.size());
  for (auto& s : sets) s.reserve(count.begin()->second);
  for (const Row& r : rows) sets[r.set].push_back({r.x, r.y});
  return sets;
}

SampleSets read_sample_points_file(const std::string& path) {
  check_plain_input(path, "sample-point table");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  return read_sample_points(in, path);
}

void write_pair_records(std::ostream& out, const std::vector<PairRecord>& pairs) {
  std::string text = "set,i,j,gd_T,gd_S,rel_err\n";
  for (const PairRecord& p : pairs) {
    text += std::to_string(p.set) + ',' + std::to_string(p.i) + ',' + std::to_string(p.j) + ',';
    append_number(text, p.on_dem);
    text += ',';
    append_number(text, p.on_mesh);
    text += ',';
    if (std::isfinite(p.on_dem) && p.on_dem > 0) {
      append_number(text, std::fabs(p.on_dem - p.on_mesh) / p.on_dem);
    }
    text += '\n';
    // note: written in chunks, so a large file needs no second copy in memory.
    if (text.size() > (1u << 16)) {
      out << text;
      text.clear();
    }
  }
  out << text;
}

}  // namespace dpts::io
