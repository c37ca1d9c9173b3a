// The one progress and cancel callback of dpts's engines (and, with the same signature, of its
// library: dpts::ProgressFn).
#pragma once

#include <functional>
#include <string_view>

namespace dpts::core {

// Called as work goes: fraction in [0, 1] of the stage named; return false to stop (the work
// then throws dpts::Cancelled).
using Progress = std::function<bool(double fraction, std::string_view stage)>;

}  // namespace dpts::core
