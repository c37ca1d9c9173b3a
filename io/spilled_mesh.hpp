// A mesh kept on disk while an engine hands it over in parts (core::MeshSink), and read back
// in runs for writing: what lets dpts-par write a mesh larger than the memory it may use.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "core/mesh.hpp"

namespace dpts::io {

// A mesh as its writers read it, in runs of consecutive vertices and faces: an in-memory
// mesh is one run of each, a spilled one many.
struct MeshParts {
  using VertexRun = std::function<void(const double* xyz, std::size_t n)>;
  using FaceRun = std::function<void(const std::array<std::uint32_t, 3>* faces, std::size_t n)>;
  const std::vector<std::string>* comments = nullptr;
  std::size_t vertices = 0, faces = 0;
  std::function<void(const VertexRun&)> each_vertices;  // every vertex once, in order
  std::function<void(const FaceRun&)> each_faces;       // every face once, in order
};

// The vertices and faces in two unnamed temporary files (in TMPDIR, else /tmp: created and
// unlinked at once, so that nothing is left behind however the process ends). About 48 bytes
// per vertex on disk (its coordinates, and its two faces or so); a few MB in memory.
class SpilledMesh : public core::MeshSink {
 public:
  // Throws IoError naming the folder when the files cannot be made.
  SpilledMesh();
  ~SpilledMesh() override;
  SpilledMesh(const SpilledMesh&) = delete;
  SpilledMesh& operator=(const SpilledMesh&) = delete;

  // Throws IoError ("temporary file in /tmp: write failed (No space left on device)").
  void add(const std::vector<double>& xyz,
           const std::vector<std::array<std::uint32_t, 3>>& faces) override;

  std::size_t vertex_count() const { return vertices_; }
  std::size_t face_count() const { return faces_; }
  // The mesh as writers read it, runs of about 1 MB; comments: the file's header comments.
  MeshParts parts(const std::vector<std::string>* comments) const;
  // The whole mesh in memory (for formats written from memory).
  core::TriMesh load() const;

 private:
  void rewind(std::FILE* f) const;
  // Runs of records (per_record values of T each) read back from f: fn(values, records).
  template <typename T, typename Fn>
  void read_runs(std::FILE* f, std::size_t records, std::size_t per_record, Fn&& fn) const;
  std::string dir_;
  std::FILE* xyz_ = nullptr;
  std::FILE* faces_file_ = nullptr;
  std::size_t vertices_ = 0, faces_ = 0;
};

}  // namespace dpts::io
