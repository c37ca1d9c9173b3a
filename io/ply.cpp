// PLY writing (binary little-endian or ASCII) and reading.
#include "io/ply.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <istream>
#include <map>
#include <ostream>
#include <sstream>

#include "core/errors.hpp"
#include "io/byte_writer.hpp"

namespace dpts::io {
namespace {

using bytes::flush;
using bytes::host_is_little_endian;
using bytes::put_le;
using bytes::put_number;
using bytes::write_failure;

}  // namespace

MeshParts parts_of(const Mesh& mesh) {
  MeshParts p;
  p.comments = &mesh.comments;
  p.vertices = mesh.vertex_count();
  p.faces = mesh.faces.size();
  p.each_vertices = [&mesh](const MeshParts::VertexRun& fn) {
    fn(mesh.xyz.data(), mesh.vertex_count());
  };
  p.each_faces = [&mesh](const MeshParts::FaceRun& fn) {
    fn(mesh.faces.data(), mesh.faces.size());
  };
  return p;
}

void write_ply(std::ostream& out, const Mesh& mesh, PlyFormat format) {
  write_ply(out, parts_of(mesh), format);
}

void write_ply(std::ostream& out, const MeshParts& mesh, PlyFormat format) {
  std::string buf;
  buf += "ply\nformat ";
  buf += format == PlyFormat::ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  for (std::string c : *mesh.comments) {
    std::replace(c.begin(), c.end(), '\n', ' ');
    std::replace(c.begin(), c.end(), '\r', ' ');
    buf += "comment " + c + "\n";
  }
  buf += "element vertex " + std::to_string(mesh.vertices) + "\n";
  buf += "property double x\nproperty double y\nproperty double z\n";
  buf += "element face " + std::to_string(mesh.faces) + "\n";
  buf += "property list uchar int vertex_indices\nend_header\n";
  constexpr std::size_t kChunk = bytes::kChunk;
  mesh.each_vertices([&](const double* xyz, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      if (format == PlyFormat::ascii) {
        bytes::put_xyz_line(buf, &xyz[3 * i]);
      } else {
        for (int k = 0; k < 3; ++k) put_le(buf, xyz[3 * i + k]);
      }
      if (buf.size() > kChunk) flush(out, buf);
    }
  });
  mesh.each_faces([&](const std::array<std::uint32_t, 3>* faces, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      const auto& f = faces[i];
      if (format == PlyFormat::ascii) {
        buf += "3 ";
        bytes::put_xyz_line(buf, f.data());
      } else {
        buf += static_cast<char>(3);
        for (int k = 0; k < 3; ++k) put_le(buf, static_cast<std::int32_t>(f[k]));
      }
      if (buf.size() > kChunk) flush(out, buf);
    }
  });
  flush(out, buf);
  out.flush();
  if (!out) throw IoError(write_failure());
}

namespace {

enum class Type { i8, u8, i16, u16, i32, u32, f32, f64 };

Type parse_type(const std::string& t, const std::string& name) {
  static const std::map<std::string, Type> types = {
      {"char", Type::i8},   {"int8", Type::i8},     {"uchar", Type::u8},   {"uint8", Type::u8},
      {"short", Type::i16}, {"int16", Type::i16},   {"ushort", Type::u16}, {"uint16", Type::u16},
      {"int", Type::i32},   {"int32", Type::i32},   {"uint", Type::u32},   {"uint32", Type::u32},
      {"float", Type::f32}, {"float32", Type::f32}, {"double", Type::f64}, {"float64", Type::f64}};
  const auto it = types.find(t);
  if (it == types.end()) throw InputError(name + ": unknown PLY type '" + t + "'");
  return it->second;
}

std::size_t type_size(Type t) {
  switch (t) {
    case Type::i8:
    case Type::u8:
      return 1;
    case Type::i16:
    case Type::u16:
      return 2;
    case Type::i32:
    case Type::u32:
    case Type::f32:
      return 4;
    case Type::f64:
      return 8;
  }
  return 0;
}

struct Property {
  std::string name;
  Type type = Type::f64;
  bool is_list = false;
  Type count_type = Type::u8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> props;
};

// Reads one value of type t from a binary stream (little or big endian).
double read_binary(std::istream& in, Type t, bool big_endian, const std::string& name) {
  char b[8];
  const std::size_t n = type_size(t);
  if (!in.read(b, static_cast<std::streamsize>(n))) throw InputError(name + ": truncated PLY data");
  if (big_endian == host_is_little_endian()) std::reverse(b, b + n);
  switch (t) {
    case Type::i8: {
      std::int8_t v;
      std::memcpy(&v, b, 1);
      return v;
    }
    case Type::u8: {
      std::uint8_t v;
      std::memcpy(&v, b, 1);
      return v;
    }
    case Type::i16: {
      std::int16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    case Type::u16: {
      std::uint16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    case Type::i32: {
      std::int32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case Type::u32: {
      std::uint32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case Type::f32: {
      float v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case Type::f64: {
      double v;
      std::memcpy(&v, b, 8);
      return v;
    }
  }
  return 0;
}

double read_ascii(std::istream& in, const std::string& name) {
  std::string tok;
  if (!(in >> tok)) throw InputError(name + ": truncated PLY data");
  double v = 0;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (res.ec != std::errc() || res.ptr != tok.data() + tok.size()) {
    throw InputError(name + ": bad number '" + tok + "' in PLY data");
  }
  return v;
}

// A PLY header: its format line's word, its elements and their properties, in order; its
// comments into `comments`.
struct Header {
  std::string format;
  std::vector<Element> elements;
};

Header read_header(std::istream& in, const std::string& name, std::vector<std::string>& comments) {
  Header h;
  std::string& format = h.format;
  std::vector<Element>& elements = h.elements;
  std::string line;
  if (!std::getline(in, line) || line.substr(0, 3) != "ply")
    throw InputError(name + ": not a PLY file");
  for (;;) {
    if (!std::getline(in, line)) throw InputError(name + ": PLY header has no end_header");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "end_header") break;
    if (key == "format") {
      ls >> format;
    } else if (key == "comment") {
      comments.push_back(line.size() > 8 ? line.substr(8) : "");
    } else if (key == "element") {
      Element e;
      long long count = -1;
      ls >> e.name >> count;
      if (count < 0) throw InputError(name + ": bad PLY element line '" + line + "'");
      // note: indices are 32-bit; a larger element cannot be a mesh we can use.
      if (count > 0xffffffffLL) throw InputError(name + ": PLY element '" + e.name + "' too large");
      e.count = static_cast<std::size_t>(count);
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) throw InputError(name + ": PLY property before any element");
      Property p;
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, it;
        ls >> ct >> it >> p.name;
        p.is_list = true;
        p.count_type = parse_type(ct, name);
        p.type = parse_type(it, name);
      } else {
        p.type = parse_type(t, name);
        ls >> p.name;
      }
      elements.back().props.push_back(p);
    }
  }
  return h;
}

}  // namespace

Mesh read_ply(std::istream& in, const std::string& name) {
  Mesh mesh;
  const Header h = read_header(in, name, mesh.comments);
  const std::string& format = h.format;
  const std::vector<Element>& elements = h.elements;
  const bool ascii = format == "ascii";
  const bool big = format == "binary_big_endian";
  if (!ascii && !big && format != "binary_little_endian") {
    throw InputError(name + ": unknown PLY format '" + format + "'");
  }
  auto value = [&](Type t) { return ascii ? read_ascii(in, name) : read_binary(in, t, big, name); };
  // A list's length: a whole number from 0 to 255 (the largest any uchar count can say; longer
  // lists with wider count types are refused rather than trusted).
  auto list_length = [&](Type t) {
    const double n = value(t);
    if (!(n >= 0 && n <= 255) || n != std::floor(n)) {
      throw InputError(name + ": bad PLY list length " + std::to_string(n));
    }
    return static_cast<std::size_t>(n);
  };
  // Counts in the header are not trusted for allocation: a truncated or lying file fails on
  // reading, not on reserving memory for elements it does not have.
  constexpr std::size_t kReserveCap = std::size_t{1} << 20;
  bool seen_vertex = false;
  for (const Element& e : elements) {
    if (e.name == "vertex") {
      int ix = -1, iy = -1, iz = -1;
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].name == "x") ix = static_cast<int>(k);
        if (e.props[k].name == "y") iy = static_cast<int>(k);
        if (e.props[k].name == "z") iz = static_cast<int>(k);
      }
      if (ix < 0 || iy < 0 || iz < 0) throw InputError(name + ": PLY vertices lack x, y or z");
      if (seen_vertex) throw InputError(name + ": PLY has two vertex elements");
      mesh.xyz.reserve(3 * std::min(e.count, kReserveCap));
      for (std::size_t i = 0; i < e.count; ++i) {
        mesh.xyz.resize(3 * (i + 1));
        for (std::size_t k = 0; k < e.props.size(); ++k) {
          const Property& p = e.props[k];
          if (p.is_list) {
            for (std::size_t m = list_length(p.count_type); m > 0; --m) value(p.type);
            continue;
          }
          const double v = value(p.type);
          if (static_cast<int>(k) == ix) mesh.xyz[3 * i] = v;
          if (static_cast<int>(k) == iy) mesh.xyz[3 * i + 1] = v;
          if (static_cast<int>(k) == iz) mesh.xyz[3 * i + 2] = v;
        }
      }
      seen_vertex = true;
    } else if (e.name == "face") {
      if (!seen_vertex) throw InputError(name + ": PLY faces come before vertices");
      if (!mesh.faces.empty()) throw InputError(name + ": PLY has two face elements");
      const bool has_indices = std::any_of(e.props.begin(), e.props.end(), [](const Property& p) {
        return p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
      });
      if (!has_indices) throw InputError(name + ": PLY faces lack a vertex_indices list");
      mesh.faces.reserve(std::min(e.count, kReserveCap));
      for (std::size_t i = 0; i < e.count; ++i) {
        for (const Property& p : e.props) {
          if (!p.is_list) {
            value(p.type);
            continue;
          }
          const std::size_t n = list_length(p.count_type);
          if (p.name != "vertex_indices" && p.name != "vertex_index") {
            for (std::size_t m = n; m > 0; --m) value(p.type);
            continue;
          }
          if (n != 3) throw InputError(name + ": face " + std::to_string(i) + " is not a triangle");
          std::array<std::uint32_t, 3> f{};
          for (int m = 0; m < 3; ++m) {
            const double idx = value(p.type);
            if (!(idx >= 0 && idx < static_cast<double>(mesh.vertex_count()))) {
              throw InputError(name + ": face " + std::to_string(i) +
                               " has vertex index out of range");
            }
            f[m] = static_cast<std::uint32_t>(idx);
          }
          mesh.faces.push_back(f);
        }
      }
    } else if (!e.props.empty()) {  // note: an element without properties has no data
      for (std::size_t i = 0; i < e.count; ++i) {
        for (const Property& p : e.props) {
          for (std::size_t m = p.is_list ? list_length(p.count_type) : 1; m > 0; --m) value(p.type);
        }
      }
    }
  }
  // Data past what the header counts: the counts do not match (a header edited, files joined).
  // Trailing white space (a line end some writers add) is allowed.
  for (int c; (c = in.get()) != std::char_traits<char>::eof();) {
    if (!std::isspace(c)) throw InputError(name + ": more data than the PLY header counts");
  }
  return mesh;
}

void check_triangles(const Mesh& mesh, const std::string& name) {
  if (mesh.faces.empty()) throw InputError(name + ": has no faces");
  for (std::size_t i = 0; i < mesh.xyz.size(); ++i) {
    if (!std::isfinite(mesh.xyz[i])) {
      throw InputError(name + ": vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
    }
  }
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const auto& f = mesh.faces[i];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      throw InputError(name + ": face " + std::to_string(i) + " repeats a vertex");
    }
  }
}

Mesh read_ply_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open");
  return read_ply(in, path);
}

}  // namespace dpts::io
