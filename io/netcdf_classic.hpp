#pragma once
// The size a netCDF classic file (CDF-1, CDF-2, CDF-5) must have to hold every value its
// header declares. Such a file cut short reads as zeros past its end, through GDAL's netCDF
// driver and the netCDF library alike, without an error.
#include <cstdint>
#include <optional>
#include <string>

namespace dpts::io {

// For the file GDAL names `name` (a plain path or a /vsi path): the bytes its header's
// variables need, or nothing when it is not a netCDF classic file (netCDF-4 is HDF5, whose
// reads fail past the end). Throws InputError for a classic header that cannot be parsed.
std::optional<std::uint64_t> netcdf_classic_needed_bytes(const std::string& name);

}  // namespace dpts::io
