// The Python module `dpts` (pybind11) over libdpts (include/dpts/dpts.hpp):
//   import dpts
//   m = dpts.simplify("dem.tif", keep=0.1)     # or a 2-D numpy array with geotransform, crs
//   m.vertices, m.faces                         # (n, 3) float64, (m, 3) uint32, read-only
//   m.write("out.gpkg")
//   dpts.evaluate("dem.tif", "out.ply", points=100, sets=3)   # dict: dpts-eval's JSON
// The GIL is released while dpts works; Ctrl-C stops it (KeyboardInterrupt).
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include "dpts/dpts.hpp"

namespace py = pybind11;

namespace {

// A progress function for the library: calls the Python callback (if any) with the GIL held,
// and sees Ctrl-C. A raised exception or a false return stops the work; the exception is
// kept, to be raised once dpts has stopped.
class PyProgress {
 public:
  explicit PyProgress(py::object callback) : callback_(std::move(callback)) {}

  dpts::ProgressFn fn() {
    return [this](double fraction, std::string_view stage) {
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) {
        error_.emplace();
        return false;
      }
      if (callback_.is_none()) return true;
      try {
        const py::object r = callback_(fraction, std::string(stage));
        return r.is_none() || r.cast<bool>();
      } catch (py::error_already_set& e) {
        error_.emplace(std::move(e));
        return false;
      }
    };
  }
  // Raises the kept exception, if any (with the GIL held).
  void rethrow() {
    if (error_) throw std::move(*error_);
  }

 private:
  py::object callback_;
  std::optional<py::error_already_set> error_;
};

// Runs f without the GIL; a stop by Ctrl-C or by the callback's exception raises that.
template <typename F>
auto without_gil(PyProgress& progress, F&& f) {
  try {
    py::gil_scoped_release release;
    return f();
  } catch (const dpts::Cancelled&) {
    progress.rethrow();
    throw;
  }
}

// A read-only (rows, 3) numpy view of the values at `data`, kept alive by `owner`.
template <typename T>
py::array view(const T* data, std::size_t rows, py::handle owner) {
  py::array a(py::dtype::of<T>(), {rows, std::size_t{3}}, {3 * sizeof(T), sizeof(T)}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

dpts::SimplifyOptions simplify_options(double keep, std::optional<std::size_t> vertices,
                                       const std::string& algo, std::optional<double> max_error,
                                       int levels, int tile_mb, int threads,
                                       const std::string& t_srs, int band) {
  dpts::SimplifyOptions o;
  o.keep = keep;
  if (vertices) o.vertices = *vertices;
  o.algo = algo;
  if (max_error) o.max_error = *max_error;
  o.levels = levels;
  o.tile_mb = tile_mb;
  o.threads = threads;
  o.t_srs = t_srs;
  o.band = band;
  return o;
}

// dpts.Mesh: the TIN handed back, its arrays as read-only numpy views.
void declare_mesh(py::module_& m) {
  py::class_<dpts::Mesh>(m, "Mesh", "A TIN: vertices x, y, z in the output CRS, faces CCW.")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const auto& mesh = self.cast<const dpts::Mesh&>();
            return view(mesh.xyz.data(), mesh.vertex_count(), self);
          },
          "(n, 3) float64, read-only (copy() to change)")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const auto& mesh = self.cast<const dpts::Mesh&>();
            static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t));
            const std::uint32_t* first = mesh.faces.empty() ? nullptr : mesh.faces.front().data();
            return view(first, mesh.faces.size(), self);
          },
          "(m, 3) uint32 vertex indices, counter-clockwise seen from above, read-only")
      .def_readonly("crs", &dpts::Mesh::crs_wkt, "the CRS as WKT ('' when none)")
      .def_readonly("comments", &dpts::Mesh::comments)
      .def_readonly("input_vertices", &dpts::Mesh::input_vertices,
                    "the DEM's surface vertices (valid cells in a face)")
      .def_readonly("warnings", &dpts::Mesh::warnings,
                    "what was read of the heights that the user should know (list of str)")
      .def(
          "write",
          [](const dpts::Mesh& mesh, const std::string& path, const std::string& format,
             bool ascii) {
            py::gil_scoped_release release;
            mesh.write(path, format, ascii);
          },
          py::arg("path"), py::arg("format") = "", py::arg("ascii") = false,
          "Writes PLY, OBJ, STL or GeoPackage (format, else the extension, else PLY); the file "
          "appears only complete.")
      .def("__repr__", [](const dpts::Mesh& mesh) {
        return "<dpts.Mesh " + std::to_string(mesh.vertex_count()) + " vertices, " +
               std::to_string(mesh.faces.size()) + " faces>";
      });
}

// dpts.simplify: a path or an array of heights to a Mesh.
void declare_simplify(py::module_& m) {
  m.def(
      "simplify",
      [](py::object source, double keep, std::optional<std::size_t> vertices,
         const std::string& algo, std::optional<double> max_error, int levels, int tile_mb,
         int threads, const std::string& t_srs, int band,
         std::optional<std::vector<double>> geotransform, const std::string& crs,
         std::optional<double> nodata, py::object progress) {
        const dpts::SimplifyOptions o = simplify_options(keep, vertices, algo, max_error, levels,
                                                         tile_mb, threads, t_srs, band);
        PyProgress p(std::move(progress));
        if (py::isinstance<py::str>(source) || py::hasattr(source, "__fspath__")) {
          const std::string path = py::str(py::module_::import("os").attr("fspath")(source));
          return without_gil(p, [&] { return dpts::simplify(path, o, p.fn()); });
        }
        if (!geotransform || geotransform->size() != 6) {
          throw py::value_error("simplify: an array needs geotransform=(x0, dx, rx, y0, ry, dy)");
        }
        const auto heights =
            py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(source);
        if (!heights || heights.ndim() != 2) {
          throw py::value_error("simplify: expected a path or a 2-D array of heights");
        }
        std::array<double, 6> gt;
        std::copy(geotransform->begin(), geotransform->end(), gt.begin());
        const double nd = nodata.value_or(std::numeric_limits<double>::quiet_NaN());
        const int rows = static_cast<int>(heights.shape(0)),
                  cols = static_cast<int>(heights.shape(1));
        return without_gil(
            p, [&] { return dpts::simplify(heights.data(), cols, rows, gt, crs, nd, o, p.fn()); });
      },
      py::arg("source"), py::kw_only(), py::arg("keep") = 0.1, py::arg("vertices") = py::none(),
      py::arg("algo") = "qem", py::arg("max_error") = py::none(), py::arg("levels") = 4,
      py::arg("tile_mb") = 256, py::arg("threads") = 0, py::arg("t_srs") = "", py::arg("band") = 1,
      py::arg("geotransform") = py::none(), py::arg("crs") = "", py::arg("nodata") = py::none(),
      py::arg("progress") = py::none(),
      R"(Simplifies a DEM into a TIN that preserves surface distances.

source: a path GDAL reads, or a 2-D array of heights (rows from the top) with geotransform
  (GDAL's six numbers), crs (WKT, 'EPSG:n', PROJ; '' none) and nodata.
keep: the fraction of the cells kept (default 0.1), or vertices=N.
algo: 'qem' (default), 'vp-meta' or 'pld-meta' (out of core); 'vp', 'pld' or 'qslim'
  (the whole DEM in memory).
progress: called as progress(fraction, stage); return False to stop (dpts.Cancelled).)");
}

// dpts.evaluate: dpts-eval's measure, as the dict of its --json.
void declare_evaluate(py::module_& m) {
  m.def(
      "evaluate",
      [](const std::string& dem, const std::string& mesh, int points, int sets, std::uint64_t seed,
         int threads, const std::string& t_srs, int band, py::object progress) {
        dpts::EvaluateOptions o;
        o.points = points;
        o.sets = sets;
        o.seed = seed;
        o.threads = threads;
        o.t_srs = t_srs;
        o.band = band;
        PyProgress p(std::move(progress));
        const dpts::Evaluation e =
            without_gil(p, [&] { return dpts::evaluate(dem, mesh, o, p.fn()); });
        return py::module_::import("json").attr("loads")(e.json);
      },
      py::arg("dem"), py::arg("mesh"), py::kw_only(), py::arg("points") = 100, py::arg("sets") = 3,
      py::arg("seed") = 1, py::arg("threads") = 0, py::arg("t_srs") = "", py::arg("band") = 1,
      py::arg("progress") = py::none(),
      "dpts-eval's measure of a mesh file (PLY, OBJ, STL or GeoPackage) against its DEM: a "
      "dict with distance_error and every other figure of dpts-eval --json.");
}

}  // namespace

PYBIND11_MODULE(dpts, m) {
  m.doc() = "dpts: distance-preserving terrain simplification (DEM -> TIN) and its measure";
  m.attr("__version__") = dpts::version();
  // note: translators are tried newest first: Cancelled before the Error it derives from.
  const auto& error = py::register_exception<dpts::Error>(m, "Error", PyExc_RuntimeError);
  py::register_exception<dpts::Cancelled>(m, "Cancelled", error.ptr());
  declare_mesh(m);
  declare_simplify(m);
  declare_evaluate(m);
}
