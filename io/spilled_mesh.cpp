// SpilledMesh: two unnamed temporary files.
#include "io/spilled_mesh.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/errors.hpp"
#include "core/temp_file.hpp"
#include "io/byte_writer.hpp"

namespace dpts::io {
namespace {

// A file made and unlinked at once in dir: its space is given back when it is closed, however
// the process ends.
std::FILE* unnamed_file(const std::string& dir) {
  const int fd = core::unnamed_temp_file(dir, "dpts-mesh");
  if (fd < 0) {
    throw IoError("temporary file in " + dir + ": cannot create (" + std::strerror(errno) + ")");
  }
  std::FILE* f = fdopen(fd, "w+b");
  if (f == nullptr) {
    close(fd);
    throw IoError("temporary file in " + dir + ": cannot open (" + std::strerror(errno) + ")");
  }
  return f;
}

constexpr std::size_t kRunBytes = std::size_t{1} << 20;

}  // namespace

SpilledMesh::SpilledMesh() {
  dir_ = core::temp_dir();
  xyz_ = unnamed_file(dir_);
  try {
    faces_file_ = unnamed_file(dir_);
  } catch (...) {
    std::fclose(xyz_);
    throw;
  }
}

SpilledMesh::~SpilledMesh() {
  std::fclose(xyz_);
  std::fclose(faces_file_);
}

void SpilledMesh::add(const std::vector<double>& xyz,
                      const std::vector<std::array<std::uint32_t, 3>>& faces) {
  errno = 0;
  // note: an empty vector's data() may be null, which fwrite must not be given.
  if ((!xyz.empty() && std::fwrite(xyz.data(), sizeof(double), xyz.size(), xyz_) != xyz.size()) ||
      (!faces.empty() &&
       std::fwrite(faces.data(), sizeof(faces[0]), faces.size(), faces_file_) != faces.size()) ||
      std::fflush(xyz_) != 0 || std::fflush(faces_file_) != 0) {
    throw IoError("temporary file in " + dir_ + ": " + bytes::write_failure());
  }
  vertices_ += xyz.size() / 3;
  faces_ += faces.size();
}

void SpilledMesh::rewind(std::FILE* f) const {
  errno = 0;
  if (std::fflush(f) != 0 || std::fseek(f, 0, SEEK_SET) != 0) {
    throw IoError("temporary file in " + dir_ + ": " + bytes::write_failure());
  }
}

// Every record of f in order, read into runs of about kRunBytes and handed to fn(run, n);
// f is left at its end, where later adds append.
template <typename T, typename Fn>
void SpilledMesh::read_runs(std::FILE* f, std::size_t records, std::size_t per_record,
                            Fn&& fn) const {
  rewind(f);
  const std::size_t per_run = std::max<std::size_t>(1, kRunBytes / (per_record * sizeof(T)));
  std::vector<T> run(per_run * per_record);
  while (records > 0) {
    const std::size_t n = std::min(records, per_run);
    if (std::fread(run.data(), per_record * sizeof(T), n, f) != n) {
      throw IoError("temporary file in " + dir_ + ": read failed");
    }
    fn(run.data(), n);
    records -= n;
  }
  std::fseek(f, 0, SEEK_END);
}

MeshParts SpilledMesh::parts(const std::vector<std::string>* comments) const {
  MeshParts p;
  p.comments = comments;
  p.vertices = vertices_;
  p.faces = faces_;
  p.each_vertices = [this](const MeshParts::VertexRun& fn) {
    read_runs<double>(xyz_, vertices_, 3, fn);
  };
  p.each_faces = [this](const MeshParts::FaceRun& fn) {
    read_runs<std::array<std::uint32_t, 3>>(faces_file_, faces_, 1, fn);
  };
  return p;
}

core::TriMesh SpilledMesh::load() const {
  core::TriMesh m;
  m.xyz.reserve(3 * vertices_);
  m.faces.reserve(faces_);
  const MeshParts p = parts(nullptr);
  p.each_vertices(
      [&](const double* xyz, std::size_t n) { m.xyz.insert(m.xyz.end(), xyz, xyz + 3 * n); });
  p.each_faces([&](const std::array<std::uint32_t, 3>* f, std::size_t n) {
    m.faces.insert(m.faces.end(), f, f + n);
  });
  return m;
}

}  // namespace dpts::io
