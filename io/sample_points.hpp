// Sample points given in a CSV file (dpts-eval --sample-points), and the per-pair distances
// written back (--pairs-out): so that other tools measure exactly the same pairs.
#pragma once

#include <array>
#include <cstdint>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

namespace dpts::io {

// Sets of points (x, y in the mesh's CRS, metres): sets[s][i] is point i of set s.
using SampleSets = std::vector<std::vector<std::array<double, 2>>>;

// Reads sample points: a header line exactly `set,x,y`, then one point per line, `set,x,y`
// (set an integer >= 0, x and y finite numbers; spaces around values and a CR before the
// newline are allowed). Point i of set s is the i-th line of set s (counting from 0); lines of
// different sets may interleave. Sets are numbered 0 to S-1 without gaps, each with at least 2
// points and all with the same number. Throws InputError naming `name` and the line (or the
// set) on the first problem.
SampleSets read_sample_points(std::istream& in, const std::string& name);
// The same from a file; a file that cannot be opened is an InputError naming it.
SampleSets read_sample_points_file(const std::string& path);

// One measured pair: points i < j of set `set`, their geodesic distance on T (the DEM's grid
// TIN) and on the mesh; +infinity where a pair is not connected.
struct PairRecord {
  std::uint32_t set = 0, i = 0, j = 0;
  double on_dem = 0, on_mesh = 0;
};

// Writes `set,i,j,gd_T,gd_S,rel_err` and one line per pair, numbers in their shortest
// round-trip form (std::to_chars; `inf` for no connection). rel_err = |gd_T - gd_S| / gd_T,
// empty where the pair is not measured (gd_T infinite or 0). Checks nothing: the caller
// checks the stream.
void write_pair_records(std::ostream& out, const std::vector<PairRecord>& pairs);

}  // namespace dpts::io
