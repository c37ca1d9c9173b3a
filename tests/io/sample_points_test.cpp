// The sample-point CSV: strict reading with one-line errors, and the per-pair CSV written back.
#include "io/sample_points.hpp"

#include <catch2/catch.hpp>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/errors.hpp"

using namespace dpts;

namespace {
io::SampleSets read(const std::string& text) {
  std::istringstream in(text);
  return io::read_sample_points(in, "pts.csv");
}
}  // namespace

TEST_CASE("sample points are read set by set in the order of their lines", "[io][sample]") {
  const auto sets = read("set,x,y\n1,10,20\n0,1.5,-2\r\n0, 3e2 ,4\n1,-7,8.25\n");
  REQUIRE(sets.size() == 2);
  CHECK(sets[0] == std::vector<std::array<double, 2>>{{1.5, -2}, {300, 4}});
  CHECK(sets[1] == std::vector<std::array<double, 2>>{{10, 20}, {-7, 8.25}});
}

TEST_CASE("a bad sample-point file is refused in one line naming the file and line",
          "[io][sample][robust]") {
  struct Case {
    std::string text, message;
  };
  const std::vector<Case> cases = {
      {"", "pts.csv: line 1: expected the header set,x,y, found an empty file"},
      {"set,x,y,z\n0,1,2\n", "pts.csv: line 1: expected the header set,x,y, found 'set,x,y,z'"},
      {"x,y\n", "pts.csv: line 1: expected the header set,x,y, found 'x,y'"},
      {"set,x,y\n", "pts.csv: line 1: no points after the header (expected lines set,x,y)"},
      {"set,x,y\n0,1,2\n0,1\n", "pts.csv: line 3: expected 3 values set,x,y, found 2"},
      {"set,x,y\n0,1,2\n0,1,2,3\n", "pts.csv: line 3: expected 3 values set,x,y, found 4"},
      {"set,x,y\n0,1,2\n\n0,1,2\n",
       "pts.csv: line 3: expected 3 values set,x,y, found 1 (an empty line)"},
      {"set,x,y\na,1,2\n", "pts.csv: line 2: set 'a': expected an integer >= 0"},
      {"set,x,y\n-1,1,2\n", "pts.csv: line 2: set '-1': expected an integer >= 0"},
      {"set,x,y\n0.5,1,2\n", "pts.csv: line 2: set '0.5': expected an integer >= 0"},
      {"set,x,y\n0,1m,2\n", "pts.csv: line 2: x '1m': expected a finite number"},
      {"set,x,y\n0,1,\n", "pts.csv: line 2: y '': expected a finite number"},
      {"set,x,y\n0,1,nan\n", "pts.csv: line 2: y 'nan': expected a finite number"},
      {"set,x,y\n0,inf,1\n", "pts.csv: line 2: x 'inf': expected a finite number"},
      {"set,x,y\n0,1,2\n0,3,4\n2,1,2\n2,3,4\n",
       "pts.csv: line 4: set 2, but set 1 has no points (sets are numbered from 0 without gaps)"},
      {"set,x,y\n1,1,2\n1,3,4\n",
       "pts.csv: line 2: set 1, but set 0 has no points (sets are numbered from 0 without gaps)"},
      {"set,x,y\n0,1,2\n0,3,4\n1,1,2\n",
       "pts.csv: line 4: set 1 has only this point (each set needs at least 2)"},
      {"set,x,y\n0,1,2\n0,3,4\n1,1,2\n1,3,4\n1,5,6\n",
       "pts.csv: line 4: set 1 has 3 points where set 0 has 2 (every set needs the same number)"},
      {"set,x,y\n99999999999999999999,1,2\n",
       "pts.csv: line 2: set '99999999999999999999': expected an integer >= 0"},
  };
  for (const auto& c : cases) {
    INFO(c.text);
    CHECK_THROWS_AS(read(c.text), InputError);
    CHECK_THROWS_WITH(read(c.text), c.message);
  }
  CHECK_THROWS_WITH(io::read_sample_points_file("/nonexistent/pts.csv"),
                    "/nonexistent/pts.csv: no such file");
}

TEST_CASE("pair records are written with round-trip numbers and rel_err where measured",
          "[io][sample]") {
  const double inf = std::numeric_limits<double>::infinity();
  std::ostringstream out;
  io::write_pair_records(out, {{0, 0, 1, 0.1, 0.30000000000000004},
                               {0, 0, 2, 1234.5678, 1234.5678},
                               {2, 3, 7, inf, inf},
                               {2, 4, 5, 0, 0}});
  const std::string expected =
      "set,i,j,gd_T,gd_S,rel_err\n"
      "0,0,1,0.1,0.30000000000000004,2.0000000000000004\n"
      "0,0,2,1234.5678,1234.5678,0\n"
      "2,3,7,inf,inf,\n"
      "2,4,5,0,0,\n";
  CHECK(out.str() == expected);
  // rel_err is |gd_T - gd_S| / gd_T, read back exactly.
  double rel = 0;
  const std::string v = "2.0000000000000004";
  std::from_chars(v.data(), v.data() + v.size(), rel);
  CHECK(rel == std::fabs(0.1 - 0.30000000000000004) / 0.1);
}
