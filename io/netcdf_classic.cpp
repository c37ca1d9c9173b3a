#include "io/netcdf_classic.hpp"

#include <cpl_vsi.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "core/errors.hpp"

namespace dpts::io {
namespace {

// The classic format, big-endian throughout (Unidata, "The NetCDF Classic Format
// Specification", and its 64-bit data extension CDF-5):
//   header = magic numrecs dim_list gatt_list var_list
//   var    = name nelems [dimid ...] vatt_list nc_type vsize begin
// Counts and lengths are 4 bytes (8 in CDF-5), begin offsets 4 bytes in CDF-1 and 8 after.
class Header {
 public:
  Header(VSILFILE* f, std::string name) : f_(f), name_(std::move(name)) {}

  std::uint64_t u(int bytes) {
    std::array<unsigned char, 8> b{};
    if (VSIFReadL(b.data(), 1, static_cast<std::size_t>(bytes), f_) !=
        static_cast<std::size_t>(bytes)) {
      fail("its header ends early");
    }
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | b[static_cast<std::size_t>(i)];
    return v;
  }
  void skip(std::uint64_t bytes) {
    if (bytes > (std::uint64_t{1} << 40)) fail("its header declares an impossible size");
    if (VSIFSeekL(f_, VSIFTellL(f_) + bytes, SEEK_SET) != 0) fail("its header ends early");
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(name_ + ": not a readable netCDF file (" + why + ")");
  }

 private:
  VSILFILE* f_;
  std::string name_;
};

std::uint64_t type_size(std::uint64_t nc_type, Header& h) {
  switch (nc_type) {
    case 1:
    case 2:
    case 7:
      return 1;  // byte, char, ubyte
    case 3:
    case 8:
      return 2;  // short, ushort
    case 4:
    case 5:
    case 9:
      return 4;  // int, float, uint
    case 6:
    case 10:
    case 11:
      return 8;  // double, int64, uint64
    default:
      h.fail("unknown value type " + std::to_string(nc_type));
  }
}

std::uint64_t padded(std::uint64_t n) { return (n + 3) / 4 * 4; }

}  // namespace

std::optional<std::uint64_t> netcdf_classic_needed_bytes(const std::string& name) {
  struct Closer {
    void operator()(VSILFILE* f) const { VSIFCloseL(f); }
  };
  std::unique_ptr<VSILFILE, Closer> file(VSIFOpenL(name.c_str(), "rb"));
  if (!file) return std::nullopt;
  std::array<char, 4> magic{};
  if (VSIFReadL(magic.data(), 1, 4, file.get()) != 4 || magic[0] != 'C' || magic[1] != 'D' ||
      magic[2] != 'F' || (magic[3] != 1 && magic[3] != 2 && magic[3] != 5)) {
    return std::nullopt;
  }
  const int version = magic[3];
  const int count = version == 5 ? 8 : 4;   // counts, lengths, dimension ids, vsize
  const int offset = version == 1 ? 4 : 8;  // begin
  Header h(file.get(), name);
  const std::uint64_t streaming = version == 5 ? ~std::uint64_t{0} : 0xFFFFFFFFu;
  const std::uint64_t numrecs = h.u(count);

  const auto name_skip = [&] { h.skip(padded(h.u(count))); };
  const auto list_start = [&](std::uint64_t tag) -> std::uint64_t {
    const std::uint64_t t = h.u(4);
    const std::uint64_t n = h.u(count);
    if (t == 0 && n == 0) return 0;  // ABSENT
    if (t != tag) h.fail("a header list has tag " + std::to_string(t));
    return n;
  };
  const auto skip_attributes = [&] {
    const std::uint64_t n = list_start(0x0C);
    for (std::uint64_t i = 0; i < n; ++i) {
      name_skip();
      const std::uint64_t type = h.u(4);
      const std::uint64_t values = h.u(count);
      h.skip(padded(values * type_size(type, h)));
    }
  };

  std::vector<std::uint64_t> dims;  // lengths; 0: the record dimension
  const std::uint64_t ndims = list_start(0x0A);
  for (std::uint64_t i = 0; i < ndims; ++i) {
    name_skip();
    dims.push_back(h.u(count));
    if (dims.size() > 65536) h.fail("too many dimensions");
  }
  skip_attributes();

  struct Var {
    bool record = false;
    std::uint64_t bytes = 0;  // per record for a record variable, unpadded
    std::uint64_t vsize = 0, begin = 0;
  };
  std::vector<Var> vars;
  const std::uint64_t nvars = list_start(0x0B);
  for (std::uint64_t i = 0; i < nvars; ++i) {
    name_skip();
    const std::uint64_t rank = h.u(count);
    Var v;
    std::uint64_t cells = 1;
    for (std::uint64_t d = 0; d < rank; ++d) {
      const std::uint64_t id = h.u(count);
      if (id >= dims.size()) h.fail("a variable names dimension " + std::to_string(id));
      if (dims[id] == 0) {
        if (d != 0) h.fail("the record dimension is not a variable's first");
        v.record = true;
      } else {
        if (dims[id] > (std::uint64_t{1} << 40) / cells) h.fail("a variable is impossibly large");
        cells *= dims[id];
      }
    }
    skip_attributes();
    v.bytes = cells * type_size(h.u(4), h);
    v.vsize = h.u(count);
    v.begin = h.u(offset);
    vars.push_back(v);
  }

  // One record holds every record variable, each padded, except a lone one (spec, "Note on
  // padding").
  std::uint64_t record_size = 0, record_vars = 0;
  for (const Var& v : vars) {
    if (v.record) {
      record_size += padded(v.bytes);
      ++record_vars;
    }
  }
  if (record_vars == 1) {
    for (const Var& v : vars) {
      if (v.record) record_size = v.bytes;
    }
  }
  std::uint64_t need = 0;
  for (const Var& v : vars) {
    if (!v.record) {
      need = std::max(need, v.begin + v.bytes);
    } else if (numrecs != streaming && numrecs > 0) {
      need = std::max(need, v.begin + (numrecs - 1) * record_size + v.bytes);
    }
  }
  return need;
}

}  // namespace dpts::io
