// Error types of dpts (include/dpts/errors.hpp, public): library code throws these, only
// main() picks an exit code.
#pragma once

#include <string>

#include "dpts/errors.hpp"

namespace dpts {

// What a DEM with no triangle of valid cells gets, after its file name (every reader and
// algorithm finds this out on its own, at a different step).
inline constexpr char kNothingToTriangulate[] =
    "no three neighbouring valid cells: nothing to triangulate";

}  // namespace dpts
