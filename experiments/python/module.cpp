// The Python module `quijibo` (docs/python.md): the toolkit's maps, grids, energy, initial guess,
// optimizer and mesher with NumPy arrays in and out, on the same libraries as the command line.
//
// Conventions of the bindings:
//   - every error is quijibo.Error with the message the command line prints after "quijibo: error: "
//   - settings are keyword arguments with the names (and defaults) of the C++ option structs and
//     the experiment files (docs/experiments.md); summaries come back as dicts (the JSON the
//     command line writes)
//   - long calls release the GIL; Ctrl-C (any Python signal handler that raises) stops them at the
//     next check (Interrupt below) and the exception reaches the caller; no partial result
//   - arrays handed out are copies (maps: read-only, assign the whole array) or, for Grid.values,
//     a view of the grid's own storage
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include "experiments/pipeline/energy.h"
#include "experiments/pipeline/experiment.h"
#include "experiments/pipeline/initial.h"
#include "experiments/pipeline/mesh.h"
#include "experiments/pipeline/julia_set.h"
#include "experiments/pipeline/modulus.h"
#include "experiments/pipeline/optimize.h"
#include "experiments/pipeline/portal.h"
#include "experiments/pipeline/run.h"
#include "experiments/pipeline/target.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "optim/optimizer.h"
#include "quijibo/energy.h"
#include "quijibo/frame.h"
#include "quijibo/grid.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/rational_map.h"
#include "quijibo/real.h"
#include "quijibo/target.h"
#include "util/error.h"
#include "util/image.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace py = pybind11;
using nlohmann::json;

namespace quijibo::python {
namespace {

// ---------------------------------------------------------------------------------------------
// JSON <-> Python

json ToJson(py::handle h, const std::string& where) {
  if (h.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
  if (py::isinstance<py::float_>(h)) return h.cast<double>();
  if (py::isinstance<py::int_>(h)) return h.cast<long long>();
  if (py::isinstance<py::str>(h)) return h.cast<std::string>();
  if (py::isinstance<py::dict>(h)) {
    json j = json::object();
    for (auto item : h.cast<py::dict>()) {
      if (!py::isinstance<py::str>(item.first)) throw Error(where + ": keys must be strings");
      const std::string key = item.first.cast<std::string>();
      j[key] = ToJson(item.second, where + "/" + key);
    }
    return j;
  }
  if (py::isinstance<py::array>(h)) return ToJson(h.attr("tolist")(), where);
  if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h)) {
    json j = json::array();
    std::size_t k = 0;
    for (auto item : h) j.push_back(ToJson(item, where + "/" + std::to_string(k++)));
    return j;
  }
  if (py::hasattr(h, "__fspath__")) return h.attr("__fspath__")().cast<std::string>();
  // NumPy scalars (numpy.int64, numpy.bool_, ...).
  if (py::hasattr(h, "item") && py::hasattr(h, "dtype")) return ToJson(h.attr("item")(), where);
  throw Error(where + ": expected a number, string, boolean, list or dict, found " +
              py::str(py::type::of(h).attr("__name__")).cast<std::string>());
}

py::object FromJson(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return py::none();
    case json::value_t::boolean: return py::bool_(j.get<bool>());
    case json::value_t::number_integer: return py::int_(j.get<std::int64_t>());
    case json::value_t::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case json::value_t::number_float: return py::float_(j.get<double>());
    case json::value_t::string: return py::str(j.get<std::string>());
    case json::value_t::array: {
      py::list l;
      for (const json& e : j) l.append(FromJson(e));
      return l;
    }
    case json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = FromJson(it.value());
      return d;
    }
    default: return py::none();
  }
}

// ---------------------------------------------------------------------------------------------
// Ctrl-C while the GIL is released.
//
// Python's own C-level handler only records a signal; its Python-level handler (KeyboardInterrupt by
// default, or the user's) runs when PyErr_CheckSignals is called on the main thread. Poll() does
// that from the work's own loops (any thread may call it; only the main thread checks, at most every
// 50 ms, re-acquiring the GIL). Once a handler has raised, Poll() returns true everywhere and the
// work winds down; Rethrow() (GIL held, after the work returned) hands the exception to Python.
class Interrupt {
 public:
  Interrupt() : main_(std::this_thread::get_id()) {}

  bool Poll() {
    if (raised_.load(std::memory_order_relaxed)) return true;
    if (std::this_thread::get_id() != main_) return false;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(50)) return false;
    last_ = now;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      error_ = std::make_unique<py::error_already_set>();
      raised_ = true;
    }
    return raised_;
  }
  bool raised() const { return raised_; }
  // With the GIL held.
  void Rethrow() {
    if (!error_) {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      return;
    }
    auto e = std::move(error_);
    throw py::error_already_set(*e);
  }

 private:
  std::thread::id main_;
  std::atomic<bool> raised_{false};
  std::chrono::steady_clock::time_point last_{};
  std::unique_ptr<py::error_already_set> error_;
};

// ---------------------------------------------------------------------------------------------
// Arrays

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

py::array_t<double> ReadOnly(py::array_t<double> a) {
  a.attr("flags").attr("writeable") = false;
  return a;
}

py::array_t<double> RootsArray(const std::vector<Vec4>& roots) {
  py::array_t<double> a({py::ssize_t(roots.size()), py::ssize_t(4)});
  auto w = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < roots.size(); ++i)
    for (int c = 0; c < 4; ++c) w(py::ssize_t(i), c) = roots[i][std::size_t(c)];
  return ReadOnly(a);
}

std::vector<Vec4> RootsFrom(const Array& a, const char* name) {
  if (a.ndim() != 2 || (a.shape(1) != 4 && a.shape(1) != 3))
    throw Error(std::string(name) + ": expected an array of shape (R, 4) (quaternions: real, i, j, k) or (R, 3) "
                "(spatial points, k = 0)");
  std::vector<Vec4> roots(std::size_t(a.shape(0)), Vec4{0, 0, 0, 0});
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (py::ssize_t c = 0; c < a.shape(1); ++c) roots[std::size_t(i)][std::size_t(c)] = r(i, c);
  return roots;
}

py::array_t<double> VectorArray(const std::vector<double>& v) {
  py::array_t<double> a(py::ssize_t(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return ReadOnly(a);
}

std::vector<double> VectorFrom(const Array& a, const char* name) {
  if (a.ndim() != 1) throw Error(std::string(name) + ": expected a one-dimensional array");
  return std::vector<double>(a.data(), a.data() + a.size());
}

template <class Real>
py::array_t<double> GradientArray(const Eigen::Matrix<Real, -1, 1>& g) {
  py::array_t<double> a(py::ssize_t(g.size()));
  for (Eigen::Index k = 0; k < g.size(); ++k) a.mutable_data()[k] = ToDouble(g[k]);
  return a;
}

void CheckMap(const RationalMap& map, const char* what) {
  if (auto why = map.Validate(); !why.empty()) throw Error(std::string(what) + ": map: " + why);
}

// A grid's values as a view (values[i, j, k], x fastest in memory) that keeps the grid alive.
py::array GridView(py::object self) {
  ScalarGrid& g = self.cast<ScalarGrid&>();
  const auto& d = g.frame.dims;
  const py::ssize_t s = sizeof(double);
  return py::array_t<double>({py::ssize_t(d[0]), py::ssize_t(d[1]), py::ssize_t(d[2])},
                             {s, s * d[0], s * d[0] * d[1]}, g.values.data(), self);
}

using FArray = py::array_t<double, py::array::f_style | py::array::forcecast>;

void SetGridValues(ScalarGrid& g, const FArray& a) {
  const auto& d = g.frame.dims;
  if (a.ndim() != 3 || a.shape(0) != d[0] || a.shape(1) != d[1] || a.shape(2) != d[2])
    throw Error("Grid.values: expected an array of shape (" + std::to_string(d[0]) + ", " + std::to_string(d[1]) +
                ", " + std::to_string(d[2]) + "), the grid's dims; make a new Grid for another shape");
  std::copy(a.data(), a.data() + a.size(), g.values.begin());
}

ScalarGrid MakeGrid(const FArray& values, const Vec3& min_corner, double spacing, const std::string& quantity,
                    const std::string& coordinates) {
  if (values.ndim() != 3) throw Error("Grid: values must be a three-dimensional array values[i, j, k]");
  ScalarGrid g;
  g.frame.dims = {int(values.shape(0)), int(values.shape(1)), int(values.shape(2))};
  g.frame.min_corner = min_corner;
  g.frame.spacing = spacing;
  if (auto why = g.frame.Validate(); !why.empty()) throw Error("Grid: " + why);
  g.values.assign(values.data(), values.data() + values.size());
  g.quantity = quantity;
  g.coordinates = coordinates;
  return g;
}

py::array_t<double> Points(const std::vector<Vec3>& p) {
  py::array_t<double> a({py::ssize_t(p.size()), py::ssize_t(3)});
  auto w = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) w(py::ssize_t(i), c) = p[i][std::size_t(c)];
  return a;
}

std::vector<Vec3> PointsFrom(const Array& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw Error(std::string(name) + ": expected an array of shape (N, 3)");
  std::vector<Vec3> p(std::size_t(a.shape(0)));
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) p[std::size_t(i)] = {r(i, 0), r(i, 1), r(i, 2)};
  return p;
}

// ---------------------------------------------------------------------------------------------
// energy

struct EnergyResult {
  double energy = 0;
  py::object gradient = py::none();
  py::dict report;
};

// `quijibo energy`'s stage (experiments/pipeline/energy.h) on an in-memory map and target; the
// keywords are its settings, read as the command line's are.
EnergyResult Energy(const RationalMap& map, const ScalarGrid& target, double alpha, const std::string& evaluator,
                    const std::string& precision, const std::string& weights, int resolution,
                    const std::string& level_weights, double slice, const std::string& mode, bool gradient,
                    const std::string& storage, int repeats) {
  CheckMap(map, "energy");
  const json settings = {{"alpha", alpha},         {"evaluator", evaluator},         {"precision", precision},
                         {"weights", weights},     {"resolution", resolution},       {"level_weights", level_weights},
                         {"slice", slice},         {"mode", mode},                   {"gradient", gradient},
                         {"storage", storage},     {"repeats", repeats}};
  const auto options = pipeline::EnergyStageOptions::FromJson(JsonReader(settings, "energy"), "", ".");
  json report;
  {
    py::gil_scoped_release release;
    report = pipeline::EnergyStage(map, target, options);
  }
  EnergyResult r;
  r.energy = report.at("energy").get<double>();
  if (gradient) {
    // The report names the entries; in the order of RationalMap.variables.
    const json& g = report.at("gradient");
    std::vector<double> v = {g.at("ln_C").get<double>(), g.at("tau").get<double>(), g.at("beta").get<double>()};
    if (g.contains("top")) {
      for (const json& e : g.at("top")) v.push_back(e.get<double>());
      for (const json& e : g.at("bottom")) v.push_back(e.get<double>());
    }
    py::array_t<double> a(py::ssize_t(v.size()));
    std::copy(v.begin(), v.end(), a.mutable_data());
    r.gradient = a;
  }
  r.report = FromJson(report);
  return r;
}

// ---------------------------------------------------------------------------------------------
// mesh

struct MeshResult {
  py::array_t<double> vertices;
  py::array_t<std::int32_t> faces;
  py::dict summary;
};

MeshResult FromTriangleMesh(const mesh::TriangleMesh& mesh, py::dict summary) {
  MeshResult r;
  r.vertices = Points(mesh.vertices);
  r.faces = py::array_t<std::int32_t>({py::ssize_t(mesh.triangles.size()), py::ssize_t(3)});
  auto f = r.faces.mutable_unchecked<2>();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) f(py::ssize_t(t), k) = mesh.triangles[t][std::size_t(k)];
  r.summary = std::move(summary);
  return r;
}

mesh::TriangleMesh ToTriangleMesh(const Array& vertices, const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& faces) {
  mesh::TriangleMesh mesh;
  mesh.vertices = PointsFrom(vertices, "vertices");
  if (faces.ndim() != 2 || faces.shape(1) != 3) throw Error("faces: expected an integer array of shape (M, 3)");
  auto f = faces.unchecked<2>();
  mesh.triangles.resize(std::size_t(faces.shape(0)));
  for (py::ssize_t t = 0; t < faces.shape(0); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t i = f(t, k);
      if (i < 0 || i >= std::int64_t(mesh.vertices.size()))
        throw Error("faces: index " + std::to_string(i) + " of face " + std::to_string(t) + " is out of range");
      mesh.triangles[std::size_t(t)][std::size_t(k)] = int(i);
    }
  return mesh;
}

// A stage's Options from keyword arguments, through its FromJson: the experiment's names, defaults,
// ranges and messages ("<function>: <JSON pointer>: <what>"); relative paths resolve against the
// working folder.
template <class O>
O OptionsFrom(const json& settings, const std::string& function, const O& start = O()) {
  return O::FromJson(JsonReader(settings, function), "", std::filesystem::current_path(), start);
}

// Keys of `settings` that `function` does not take (the stage's run-only settings), as an error.
void Refuse(const json& settings, const std::string& function, const std::vector<std::string>& keys,
            const std::string& why) {
  for (const std::string& k : keys)
    if (settings.contains(k)) throw Error(function + ": /" + k + ": " + why);
}

MeshResult Mesh(const RationalMap& map, int resolution, int iterations, bool allow_empty, py::kwargs kwargs) {
  CheckMap(map, "mesh");
  json settings = ToJson(kwargs, "mesh");
  Refuse(settings, "mesh", {"enabled", "optimizer", "vdb", "obj", "vdb_grids", "vdb_band", "ply_double"},
         "a setting of `quijibo run`'s mesh files; write the result with write_mesh");
  settings["resolution"] = resolution;
  settings["iterations"] = iterations;
  const pipeline::MeshStageOptions options = OptionsFrom<pipeline::MeshStageOptions>(settings, "mesh");
  Interrupt interrupt;
  // The local mesher on a field that, once interrupted, skips the remaining batches (NaN:
  // outside); the mesh is then dropped.
  const pipeline::Mesher mesher = [&interrupt](const mesh::BatchField& field, const mesh::MeshingOptions& o,
                                               mesh::MeshingSummary* s, mesh::FieldBand* band, mesh::TriangleMesh* mesh,
                                               mesh::JuliaFieldStats* stats) {
    mesh::BatchField polled = field;
    polled.evaluate = [inner = field.evaluate, &interrupt](const Vec3* p, std::size_t n, double* v) {
      if (interrupt.Poll()) {
        std::fill(v, v + n, std::numeric_limits<double>::quiet_NaN());
        return;
      }
      inner(p, n, v);
    };
    return pipeline::LocalMesher(polled, o, s, band, mesh, stats);
  };
  pipeline::MeshStageResult r;
  {
    py::gil_scoped_release release;
    r = pipeline::MeshJulia(options.Iterated(map), options, mesher);
  }
  interrupt.Rethrow();
  if (r.empty() && !allow_empty)
    throw Error("mesh: the surface log|q_n| = " + std::to_string(options.iso) +
                " does not cross the box (no triangles); allow_empty=True returns the empty mesh");
  // The summary `quijibo mesh` prints, without the file names.
  json summary = pipeline::MeshSummary(r, options, "", pipeline::MeshFiles{});
  summary.erase("map");
  summary.erase("out");
  return FromTriangleMesh(r.mesh, FromJson(summary));
}

// ---------------------------------------------------------------------------------------------
// optimize

// Hands every record of the run (a log.jsonl line, as a dict) to a Python callable; a true result
// aborts the run (optim/iteration_callback.h), an exception aborts it and is raised afterwards.
class PythonCallback : public optim::IterationCallback {
 public:
  // Made and destroyed with the GIL held.
  explicit PythonCallback(py::object fn) : fn_(std::move(fn)) {}
  optim::CallbackReturnType operator()(const optim::IterationSummary& s) override {
    if (stopped_) return optim::CallbackReturnType::kAbort;
    py::gil_scoped_acquire gil;
    try {
      if (py::bool_(fn_(FromJson(s.ToJson())))) stopped_ = true;
    } catch (py::error_already_set& e) {
      error_ = std::make_unique<py::error_already_set>(std::move(e));
      stopped_ = true;
    }
    return stopped_ ? optim::CallbackReturnType::kAbort : optim::CallbackReturnType::kContinue;
  }
  // With the GIL held: the callback's exception, if it raised one.
  void Rethrow() {
    if (error_) {
      auto e = std::move(error_);
      throw py::error_already_set(*e);
    }
  }

 private:
  py::object fn_;
  bool stopped_ = false;
  std::unique_ptr<py::error_already_set> error_;
};

// The optimize stage, as `quijibo optimize` runs it; without `out` nothing is written.
py::tuple OptimizeMap(const ScalarGrid& target, const RationalMap& initial, py::object schedule, py::object callback,
                      py::object out, bool resume, py::kwargs settings) {
  CheckMap(initial, "optimize");
  json j = ToJson(settings, "optimize");
  if (!schedule.is_none()) j["schedule"] = ToJson(schedule, "optimize/schedule");
  pipeline::OptimizeStageOptions stage =
      pipeline::OptimizeStageOptions::FromJson(JsonReader(j, "optimize"), "", std::filesystem::current_path(), false);
  if (out.is_none() && resume) throw Error("optimize: resume=True needs the folder of the interrupted run (out=...)");
  const std::string out_dir = out.is_none() ? "" : ToJson(out, "optimize/out").get<std::string>();
  std::unique_ptr<PythonCallback> observer;
  if (!callback.is_none()) {
    if (!PyCallable_Check(callback.ptr())) throw Error("optimize: callback must be callable");
    observer = std::make_unique<PythonCallback>(callback);
    stage.optimizer.callbacks.push_back(observer.get());
  }
  if (auto why = stage.optimizer.Validate(); !why.empty()) throw Error("optimize: " + why);
  pipeline::OptimizeStageResult r;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    try {
      r = pipeline::OptimizeStage(target, initial, stage, out_dir, resume);
    } catch (const Interrupted&) {
      interrupted = true;
    }
  }
  if (observer) observer->Rethrow();
  if (interrupted) {
    const std::string where = out_dir.empty() ? "" : "; checkpoint written to " + out_dir +
                                                          "/checkpoint.json, continue with resume=True";
    PyErr_SetString(PyExc_KeyboardInterrupt, ("optimize: interrupted" + where).c_str());
    throw py::error_already_set();
  }
  json report = r.summary.ToJson(stage.optimizer);
  if (!r.summary.complete) report["stop_reason"] = r.summary.stop_reason;
  return py::make_tuple(r.map, FromJson(report));
}

// ---------------------------------------------------------------------------------------------
// target, initial guess

py::array_t<std::uint8_t> ImageArray(const Image& image) {
  py::array_t<std::uint8_t> a({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(3)});
  auto w = a.mutable_unchecked<3>();
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const Rgb& c = image.pixels[std::size_t(y) * std::size_t(image.width) + std::size_t(x)];
      w(y, x, 0) = c.r, w(y, x, 1) = c.g, w(y, x, 2) = c.b;
    }
  return a;
}

struct TargetHandle {
  ScalarGrid grid;
  FractalFrame frame;
  std::string source;
  py::object mesh = py::none();  // mesh targets: the mesh in the fractal frame
  double sdf_seconds = 0;
};

TargetHandle FromTargetResult(const pipeline::TargetResult& t) {
  TargetHandle h;
  h.grid = t.grid;
  h.frame = t.frame;
  h.source = t.source;
  if (!t.mesh.triangles.empty()) h.mesh = py::cast(FromTriangleMesh(t.mesh, py::dict()));
  h.sdf_seconds = t.sdf_seconds;
  return h;
}

TargetHandle MakeTarget(py::kwargs kwargs) {
  const pipeline::TargetOptions options = OptionsFrom<pipeline::TargetOptions>(ToJson(kwargs, "target"), "target");
  pipeline::TargetResult t;
  {
    py::gil_scoped_release release;
    t = pipeline::Target(options);
  }
  return FromTargetResult(t);
}

struct InitialGuessHandle {
  RationalMap map;
  TargetHandle target;
  py::object summary = py::none();
  py::object picture = py::none();
};

InitialGuessHandle MakeInitialGuess(const std::string& mesh_path, py::kwargs kwargs) {
  // The target's settings (resolution, padding, box, origin, ...) and the guess's, told apart by
  // the target's schema.
  const json all = ToJson(kwargs, "initial_guess");
  json target = {{"mesh", mesh_path}}, initial = json::object();
  std::set<std::string> target_keys;
  for (const auto& s : pipeline::TargetOptions::Settings().settings()) target_keys.insert(s.key);
  for (auto it = all.begin(); it != all.end(); ++it) {
    if (it.key() == "mesh" || it.key() == "qgrid" || it.key() == "analytic")
      throw Error("initial_guess: /" + it.key() + ": the target is the mesh given first");
    (target_keys.count(it.key()) ? target : initial)[it.key()] = it.value();
  }
  const pipeline::TargetOptions target_options = OptionsFrom<pipeline::TargetOptions>(target, "initial_guess");
  const pipeline::InitialGuessStageOptions options =
      OptionsFrom<pipeline::InitialGuessStageOptions>(initial, "initial_guess");
  pipeline::TargetResult t;
  pipeline::InitialGuessResult g;
  {
    py::gil_scoped_release release;
    t = pipeline::Target(target_options);
    g = pipeline::InitialGuess(t, options);
  }
  InitialGuessHandle h;
  h.map = std::move(g.map);
  h.target = FromTargetResult(t);
  h.summary = FromJson(g.summary);
  if (g.picture) h.picture = ImageArray(*g.picture);
  return h;
}

// ---------------------------------------------------------------------------------------------
// shape modulus, portals

struct ProductHandle {
  std::string kind;  // "ply" or "png"
  py::object mesh = py::none();
  py::object image = py::none();
  py::dict report;
};

ProductHandle FromProduct(const pipeline::Product& p, const json& report) {
  ProductHandle h;
  h.kind = p.kind;
  if (p.kind == "ply") h.mesh = py::cast(FromTriangleMesh(p.mesh, FromJson(p.report)));
  else h.image = ImageArray(p.image);
  h.report = FromJson(report);
  return h;
}

std::string OptionalPath(py::object out, const std::string& fallback) {
  return out.is_none() ? fallback : ToJson(out, "out").get<std::string>();
}

ProductHandle ShapeModulus(const std::string& target, py::object out, py::kwargs kwargs) {
  const pipeline::ModulusStageOptions options =
      OptionsFrom<pipeline::ModulusStageOptions>(ToJson(kwargs, "modulus"), "modulus");
  // Without `out`, the output format decides 2D or 3D as the file's extension would.
  const std::string path = OptionalPath(out, "modulus." + options.output.format);
  pipeline::ModulusStageResult r;
  {
    py::gil_scoped_release release;
    r = pipeline::Modulus(target, options, path);
    if (!out.is_none()) pipeline::WriteModulus(r, path, "");
  }
  return FromProduct(r.product, r.report);
}

ProductHandle Portal(py::object out, py::kwargs kwargs) {
  const pipeline::PortalStageOptions options =
      OptionsFrom<pipeline::PortalStageOptions>(ToJson(kwargs, "portal"), "portal");
  const std::string path = OptionalPath(out, "portal." + options.output.format);
  pipeline::PortalStageResult r;
  {
    py::gil_scoped_release release;
    r = pipeline::Portal(options, path);
    if (!out.is_none()) pipeline::WritePortal(r, path, "", "");
  }
  return FromProduct(r.product, r.report);
}

// The Julia set of a map of any kind (methods/map_kind.h), as `quijibo julia` and the "julia"
// experiment method make it; out= decides 2D or 3D by its extension, as the command's -o does.
ProductHandle JuliaSetOf(py::object map, py::object out, py::kwargs kwargs) {
  json settings = ToJson(kwargs, "julia");
  settings["map"] = ToJson(map, "julia/map");
  pipeline::JuliaSetStageOptions options =
      pipeline::JuliaSetStageOptions::FromJson(JsonReader(settings, "julia"), "", std::filesystem::current_path());
  const std::string path = OptionalPath(out, "julia." + options.output.format);
  if (!out.is_none()) options.output.format = HasExtension(path, ".ply") ? "ply" : "png";
  pipeline::JuliaSetStageResult r;
  {
    py::gil_scoped_release release;
    r = pipeline::JuliaSet(options);
    if (!out.is_none()) pipeline::WriteProduct(r.product, path);
  }
  return FromProduct(r.product, r.report);
}

// ---------------------------------------------------------------------------------------------
// run

py::dict Run(py::object experiment, py::object out, bool resume, bool check, bool quiet) {
  pipeline::Experiment e;
  if (py::isinstance<py::dict>(experiment))
    e = pipeline::Experiment::FromJson(ToJson(experiment, "experiment"), "experiment", std::filesystem::current_path());
  else
    e = pipeline::Experiment::FromFile(ToJson(experiment, "experiment").get<std::string>());
  pipeline::RunOptions options;
  options.out_dir = OptionalPath(out, "");
  options.resume = resume;
  options.check_only = check;
  options.quiet = quiet;
  pipeline::RunSummary s;
  {
    py::gil_scoped_release release;
    s = pipeline::RunExperiment(e, options);
  }
  // A Ctrl-C during a stage that does not look for it takes effect now.
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  json stages = json::array();
  for (const pipeline::StageRecord& r : s.stages)
    stages.push_back({{"name", r.name}, {"status", r.status}, {"hash", r.hash}, {"seconds", r.seconds}});
  return FromJson({{"results", s.results}, {"seconds", s.seconds}, {"stages", stages}, {"resolved", s.resolved}});
}

// Frames.
void BindFrames(py::module_& m) {
  py::class_<FractalFrame>(m, "Frame",
                           "The user -> normalized -> fractal frame (quijibo/frame.h): w = fractal_radius * "
                           "(scale * x + translation - origin).")
      .def(py::init<>())
      .def_readwrite("fractal_radius", &FractalFrame::fractal_radius)
      .def_readwrite("padding", &FractalFrame::padding)
      .def_readwrite("scale", &FractalFrame::scale)
      .def_readwrite("translation", &FractalFrame::translation, "(3,) assign the whole triple")
      .def_readwrite("origin", &FractalFrame::origin, "normalized point at the fractal origin; assign the whole triple")
      .def_property_readonly("box_center", &FractalFrame::box_center,
                             "centre of the normalized unit cube in the fractal frame")
      .def(
          "user_to_fractal",
          [](const FractalFrame& f, const Array& p) {
            std::vector<Vec3> v = PointsFrom(p, "user_to_fractal");
            for (Vec3& x : v) x = f.user_to_fractal(x);
            return Points(v);
          },
          py::arg("points"), "(N, 3) points of the user frame -> fractal frame")
      .def(
          "fractal_to_user",
          [](const FractalFrame& f, const Array& p) {
            std::vector<Vec3> v = PointsFrom(p, "fractal_to_user");
            for (Vec3& x : v) x = f.fractal_to_user(x);
            return Points(v);
          },
          py::arg("points"), "(N, 3) points of the fractal frame -> user frame")
      .def("__repr__", [](const FractalFrame& f) {
        return "Frame(fractal_radius=" + std::to_string(f.fractal_radius) + ", scale=" + std::to_string(f.scale) +
               ", origin=(" + std::to_string(f.origin[0]) + ", " + std::to_string(f.origin[1]) + ", " +
               std::to_string(f.origin[2]) + "))";
      });
}

// Rational maps.
void BindMaps(py::module_& m) {
  py::class_<RationalMap>(m, "RationalMap",
                          "R(q) = e^C T(q) B(q)^-1 (2015 Eqns 4, 8; quijibo/rational_map.h). Roots are (R, 4) "
                          "arrays of quaternions (real, i, j, k) in the fractal frame; arrays read back are "
                          "read-only copies: assign a whole array to change them.")
      .def(py::init([](py::object top_roots, py::object top_exponents, py::object bottom_roots,
                       py::object bottom_exponents, double ln_C, double tau, double beta) {
             RationalMap map;
             if (!top_roots.is_none()) map.top_roots = RootsFrom(top_roots.cast<Array>(), "top_roots");
             if (!bottom_roots.is_none()) map.bottom_roots = RootsFrom(bottom_roots.cast<Array>(), "bottom_roots");
             if (!top_exponents.is_none()) map.top_exponents = VectorFrom(top_exponents.cast<Array>(), "top_exponents");
             else map.top_exponents.assign(map.top_roots.size(), 1.0);
             if (!bottom_exponents.is_none())
               map.bottom_exponents = VectorFrom(bottom_exponents.cast<Array>(), "bottom_exponents");
             else map.bottom_exponents.assign(map.bottom_roots.size(), 1.0);
             map.ln_C = ln_C;
             map.tau = tau;
             map.beta = beta;
             CheckMap(map, "RationalMap");
             return map;
           }),
           py::kw_only(), py::arg("top_roots") = py::none(), py::arg("top_exponents") = py::none(),
           py::arg("bottom_roots") = py::none(), py::arg("bottom_exponents") = py::none(),
           py::arg("ln_C") = RationalMap{}.ln_C, py::arg("tau") = RationalMap{}.tau,
           py::arg("beta") = RationalMap{}.beta,
           "A map from its roots (exponents default to 1) and ln C, tau, beta.")
      .def_property(
          "top_roots", [](const RationalMap& m) { return RootsArray(m.top_roots); },
          [](RationalMap& m, const Array& a) { m.top_roots = RootsFrom(a, "top_roots"); })
      .def_property(
          "bottom_roots", [](const RationalMap& m) { return RootsArray(m.bottom_roots); },
          [](RationalMap& m, const Array& a) { m.bottom_roots = RootsFrom(a, "bottom_roots"); })
      .def_property(
          "top_exponents", [](const RationalMap& m) { return VectorArray(m.top_exponents); },
          [](RationalMap& m, const Array& a) { m.top_exponents = VectorFrom(a, "top_exponents"); })
      .def_property(
          "bottom_exponents", [](const RationalMap& m) { return VectorArray(m.bottom_exponents); },
          [](RationalMap& m, const Array& a) { m.bottom_exponents = VectorFrom(a, "bottom_exponents"); })
      .def_readwrite("ln_C", &RationalMap::ln_C)
      .def_readwrite("tau", &RationalMap::tau)
      .def_readwrite("beta", &RationalMap::beta)
      .def_readwrite("leading_zero_roots", &RationalMap::leading_zero_roots)
      .def_readwrite("frame", &RationalMap::frame)
      .def_property(
          "provenance", [](const RationalMap& m) { return FromJson(m.provenance); },
          [](RationalMap& m, py::dict d) { m.provenance = ToJson(d, "provenance"); },
          "how the map was made (a dict; a copy: assign a whole dict to change it)")
      .def_property(
          "variables",
          [](const RationalMap& m) {
            const Eigen::VectorXd x = m.variables();
            return ReadOnly(GradientArray(x));
          },
          [](RationalMap& m, const Array& a) {
            const std::vector<double> v = VectorFrom(a, "variables");
            m.set_variables(Eigen::Map<const Eigen::VectorXd>(v.data(), Eigen::Index(v.size())));
          },
          "the optimization variables [ln C, tau, beta, T_1..T_nt, B_1..B_nb] (the gradient's order)")
      .def_property_readonly("top_count", &RationalMap::top_count)
      .def_property_readonly("bottom_count", &RationalMap::bottom_count)
      .def_property_readonly("variable_count", &RationalMap::variable_count)
      .def(
          "validate", [](const RationalMap& m) { CheckMap(m, "RationalMap"); },
          "raise quijibo.Error when the map is inconsistent (counts, signs, finiteness)")
      .def(
          "one_step_log_modulus",
          [](const RationalMap& m, const Array& p, double slice) {
            CheckMap(m, "one_step_log_modulus");
            const std::vector<Vec3> pts = PointsFrom(p, "one_step_log_modulus");
            py::array_t<double> out(py::ssize_t(pts.size()));
            for (std::size_t i = 0; i < pts.size(); ++i) out.mutable_data()[i] = OneStepLogModulus(m, pts[i], slice);
            return out;
          },
          py::arg("points"), py::arg("slice") = 0.0,
          "L = log|R(q)| after one application at the (N, 3) fractal-frame points; the one-step set is L < 0")
      .def("to_json", [](const RationalMap& m) { return FromJson(MapToJson(m)); }, "the map.json document as a dict")
      .def_static(
          "from_json", [](py::dict d) { return MapFromJson(ToJson(d, "map"), "map"); }, py::arg("document"),
          "a map from a map.json document (a dict)")
      .def("copy", [](const RationalMap& m) { return RationalMap(m); })
      .def("__copy__", [](const RationalMap& m) { return RationalMap(m); })
      .def("__deepcopy__", [](const RationalMap& m, py::dict) { return RationalMap(m); })
      .def("__repr__", [](const RationalMap& m) {
        return "RationalMap(" + std::to_string(m.top_count()) + " top roots, " + std::to_string(m.bottom_count()) +
               " bottom roots, ln_C=" + std::to_string(m.ln_C) + ", tau=" + std::to_string(m.tau) +
               ", beta=" + std::to_string(m.beta) + ")";
      });

  m.def(
      "read_map", [](const std::string& path) { return ReadMap(path); }, py::arg("path"),
      "Read a map.json (strict: errors name the file and JSON pointer).");
  m.def(
      "write_map", [](const RationalMap& map, const std::string& path) { WriteMap(path, map); }, py::arg("map"),
      py::arg("path"), "Write a map.json atomically.");
  m.def(
      "random_map",
      [](int top, int bottom, double root_radius, double exponent_min, double exponent_max, double ln_C,
         bool leading_zero_roots, std::uint64_t seed) {
        RandomMapOptions o;
        o.top = top;
        o.bottom = bottom;
        o.root_radius = root_radius;
        o.exponent_min = exponent_min;
        o.exponent_max = exponent_max;
        o.ln_C = ln_C;
        o.leading_zero_roots = leading_zero_roots;
        o.seed = seed;
        return RandomMap(o);
      },
      py::kw_only(), py::arg("top") = RandomMapOptions{}.top, py::arg("bottom") = RandomMapOptions{}.bottom,
      py::arg("root_radius") = RandomMapOptions{}.root_radius,
      py::arg("exponent_min") = RandomMapOptions{}.exponent_min,
      py::arg("exponent_max") = RandomMapOptions{}.exponent_max, py::arg("ln_C") = RandomMapOptions{}.ln_C,
      py::arg("leading_zero_roots") = RandomMapOptions{}.leading_zero_roots,
      py::arg("seed") = RandomMapOptions{}.seed,
      "A seeded random map (`quijibo map random`): roots uniform in a ball on k = 0, exponents uniform.");
}

// Grids.
void BindGrids(py::module_& m) {
  py::class_<ScalarGrid>(m, "Grid",
                         "Values at the cell centres of a regular grid (quijibo/grid.h): values[i, j, k] at "
                         "min_corner + spacing * (i + 1/2, j + 1/2, k + 1/2).")
      .def(py::init(&MakeGrid), py::arg("values"), py::arg("min_corner"), py::arg("spacing"),
           py::arg("quantity") = ScalarGrid{}.quantity, py::arg("coordinates") = ScalarGrid{}.coordinates)
      .def_property(
          "values", [](py::object self) { return GridView(self); }, &SetGridValues,
          "(nx, ny, nz) view of the grid's storage (writes go to the grid); assign an array of the same shape")
      .def_property_readonly("dims", [](const ScalarGrid& g) { return g.frame.dims; })
      .def_property(
          "min_corner", [](const ScalarGrid& g) { return g.frame.min_corner; },
          [](ScalarGrid& g, const Vec3& c) { g.frame.min_corner = c; })
      .def_property(
          "spacing", [](const ScalarGrid& g) { return g.frame.spacing; },
          [](ScalarGrid& g, double h) {
            GridFrame f = g.frame;
            f.spacing = h;
            if (auto why = f.Validate(); !why.empty()) throw Error("Grid.spacing: " + why);
            g.frame = f;
          })
      .def_readwrite("quantity", &ScalarGrid::quantity)
      .def_readwrite("coordinates", &ScalarGrid::coordinates)
      .def(
          "cell_centers",
          [](const ScalarGrid& g) {
            const auto& d = g.frame.dims;
            py::array_t<double> a({py::ssize_t(d[0]), py::ssize_t(d[1]), py::ssize_t(d[2]), py::ssize_t(3)});
            auto w = a.mutable_unchecked<4>();
            for (int k = 0; k < d[2]; ++k)
              for (int j = 0; j < d[1]; ++j)
                for (int i = 0; i < d[0]; ++i) {
                  const Vec3 p = g.frame.cell_center(i, j, k);
                  for (int c = 0; c < 3; ++c) w(i, j, k, c) = p[std::size_t(c)];
                }
            return a;
          },
          "(nx, ny, nz, 3) the sample points")
      .def(
          "sample",
          [](const ScalarGrid& g, const Array& p) {
            const std::vector<Vec3> pts = PointsFrom(p, "Grid.sample");
            py::array_t<double> out(py::ssize_t(pts.size()));
            for (std::size_t i = 0; i < pts.size(); ++i) out.mutable_data()[i] = g.sample(pts[i]);
            return out;
          },
          py::arg("points"), "trilinear interpolation between cell centres at (N, 3) points, clamped at the border")
      .def("copy", [](const ScalarGrid& g) { return ScalarGrid(g); })
      .def("__copy__", [](const ScalarGrid& g) { return ScalarGrid(g); })
      .def("__deepcopy__", [](const ScalarGrid& g, py::dict) { return ScalarGrid(g); })
      .def("__repr__", [](const ScalarGrid& g) {
        const auto& d = g.frame.dims;
        return "Grid(" + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]) +
               ", spacing=" + std::to_string(g.frame.spacing) + ", quantity=" + g.quantity + ")";
      });

  m.def(
      "read_grid", [](const std::string& path) { return ReadGrid(path); }, py::arg("path"), "Read a .qgrid file.");
  m.def(
      "write_grid", [](const ScalarGrid& g, const std::string& path) { WriteGrid(path, g); }, py::arg("grid"),
      py::arg("path"), "Write a .qgrid file atomically.");
  py::class_<TargetHandle>(m, "Target",
                           "The target stage's result: the signed distance Grid the energy fits, the frame and, for "
                           "mesh targets, the mesh in the fractal frame.")
      .def_readonly("grid", &TargetHandle::grid)
      .def_readonly("frame", &TargetHandle::frame)
      .def_readonly("source", &TargetHandle::source)
      .def_readonly("mesh", &TargetHandle::mesh)
      .def_readonly("sdf_seconds", &TargetHandle::sdf_seconds)
      .def("__repr__", [](const TargetHandle& t) { return "Target(" + t.source + ")"; });
  m.def("target", &MakeTarget,
        "The target stage of an experiment (its `target` object's keys): exactly one of mesh= (.obj, .ply, .stl, "
        ".off: normalized, origin placed, its signed distance on the target grid), qgrid= (a .qgrid) or analytic= "
        "('sphere[:radius=R]', 'torus[:major=R,minor=r]'); resolution=, padding=, fractal_radius=, box=, origin=.");
}

// Energy.
void BindEnergy(py::module_& m) {
  py::class_<EnergyResult>(m, "EnergyResult", "psi and its gradient (quijibo/energy.h)")
      .def_readonly("energy", &EnergyResult::energy, "psi: the same double `quijibo energy` prints")
      .def_readonly("gradient", &EnergyResult::gradient,
                    "d psi / d x in the order of RationalMap.variables (3 entries in mode 'variable'); None "
                    "without gradient")
      .def_readonly("report", &EnergyResult::report,
                    "the JSON report of `quijibo energy` as a dict: cells, singular and overflowed cells, "
                    "seconds, exact decimal strings, ...")
      .def("__repr__", [](const EnergyResult& r) {
        std::ostringstream s;
        s.precision(17);
        s << "EnergyResult(energy=" << r.energy << ")";
        return s.str();
      });
  const pipeline::EnergyStageOptions energy_defaults;
  m.def("energy", &Energy, py::arg("map"), py::arg("grid"), py::kw_only(),
        py::arg("alpha") = energy_defaults.energy.alpha, py::arg("evaluator") = energy_defaults.evaluator,
        py::arg("precision") = PrecisionName(energy_defaults.precision),
        py::arg("weights") = WeightFieldName(energy_defaults.weights), py::arg("resolution") = energy_defaults.resolution,
        py::arg("level_weights") = LevelWeightsName(energy_defaults.level_weights),
        py::arg("slice") = energy_defaults.slice,
        py::arg("mode") = std::string(energy_defaults.mode == EnergyMode::kFull ? "full" : "variable"),
        py::arg("gradient") = energy_defaults.gradient, py::arg("storage") = StorageName(energy_defaults.storage),
        py::arg("repeats") = energy_defaults.repeats,
        "psi = (1/eta) sum -tanh(alpha L) W of `map` on the target `grid` (a signed distance Grid), as `quijibo "
        "energy`: evaluator dense (log-linear, exact, double; also: loglinear) or cached (the paper's, any "
        "precision), weights layer/inverse/balanced, resolution 0 = the target's own grid, mode full or variable "
        "(V pass).");
}

// Initial guess.
void BindInitialGuess(py::module_& m) {
  py::class_<InitialGuessHandle>(m, "InitialGuess",
                                 "The initial map and its target; unpacks as (map, target grid).")
      .def_readonly("map", &InitialGuessHandle::map)
      .def_property_readonly("target", [](const InitialGuessHandle& h) { return h.target.grid; })
      .def_property_readonly("frame", [](const InitialGuessHandle& h) { return h.target.frame; })
      .def_readonly("summary", &InitialGuessHandle::summary, "monopoles.json: the start check, the fit, seconds")
      .def_readonly("picture", &InitialGuessHandle::picture,
                    "start.png (log-kernel) or potential.png (monopoles) as an (H, W, 3) uint8 array")
      .def("__len__", [](const InitialGuessHandle&) { return 2; })
      .def("__iter__", [](const InitialGuessHandle& h) { return py::iter(py::make_tuple(h.map, h.target.grid)); })
      .def("__getitem__", [](const InitialGuessHandle& h, int k) -> py::object {
        if (k == 0 || k == -2) return py::cast(h.map);
        if (k == 1 || k == -1) return py::cast(h.target.grid);
        throw py::index_error("InitialGuess unpacks as (map, target)");
      });
  m.def("initial_guess", &MakeInitialGuess, py::arg("mesh"),
        "The initial map for a mesh (`quijibo monopoles`, the experiment's initial stage): by default the "
        "log-kernel fit (kind='log-kernel'; roots=, max_roots=, root_spacing=, root_offset=, band=, "
        "band_amplitude=, ridge=, refine_rounds=, origin_root=, sampling_seed=) or the paper's monopoles "
        "(kind='monopoles'; epsilon=, fit_target=, amplitude=, ...); the target grid's settings (resolution=, "
        "padding=, fractal_radius=, box=, origin=) as the experiment's target. Returns an InitialGuess: "
        "(map, target grid).");
}

// Mesh.
void BindMesh(py::module_& m) {
  py::class_<MeshResult>(m, "Mesh", "A triangle mesh: vertices (N, 3), faces (M, 3); unpacks as (vertices, faces)")
      .def(py::init([](const Array& v, const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& f) {
             return FromTriangleMesh(ToTriangleMesh(v, f), py::dict());
           }),
           py::arg("vertices"), py::arg("faces"))
      .def_readonly("vertices", &MeshResult::vertices)
      .def_readonly("faces", &MeshResult::faces)
      .def_readonly("summary", &MeshResult::summary)
      .def("__len__", [](const MeshResult&) { return 2; })
      .def("__iter__",
           [](const MeshResult& r) { return py::iter(py::make_tuple(r.vertices, r.faces)); })
      .def("__getitem__", [](const MeshResult& r, int k) -> py::object {
        if (k == 0 || k == -2) return r.vertices;
        if (k == 1 || k == -1) return r.faces;
        throw py::index_error("Mesh unpacks as (vertices, faces)");
      });
  m.def(
      "read_mesh",
      [](const std::string& path) {
        mesh::MeshReadReport report;
        mesh::TriangleMesh mesh;
        {
          py::gil_scoped_release release;
          mesh = mesh::ReadMesh(path, &report);
        }
        return FromTriangleMesh(mesh, FromJson({{"faces_read", report.faces_read},
                                                {"degenerate_dropped", report.degenerate_dropped},
                                                {"non_triangles_ignored", report.non_triangles_ignored},
                                                {"corners_welded", report.corners_welded}}));
      },
      py::arg("path"), "Read a mesh (.obj, .ply, .stl, .off) as quijibo does: welded, degenerate faces dropped.");
  m.def(
      "write_mesh",
      [](py::object mesh, const std::string& path, bool double_precision) {
        const py::tuple vf = py::tuple(mesh);
        if (vf.size() != 2) throw Error("write_mesh: expected a Mesh or (vertices, faces)");
        const mesh::TriangleMesh t = ToTriangleMesh(vf[0].cast<Array>(), vf[1].cast<py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>>());
        const std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
        if (ext == ".obj" || ext == ".OBJ") mesh::WriteObj(path, t);
        else if (ext == ".ply" || ext == ".PLY") mesh::WritePly(path, t, double_precision ? mesh::PlyPrecision::kFloat64 : mesh::PlyPrecision::kFloat32);
        else throw Error(path + ": the mesh must end in .ply or .obj");
      },
      py::arg("mesh"), py::arg("path"), py::kw_only(), py::arg("double") = false,
      "Write a Mesh (or a (vertices, faces) pair) as binary PLY (float, or double with double=True) or OBJ, "
      "atomically.");
}

// Shape modulus, portals, experiments.
void BindStages(py::module_& m) {
  py::class_<ProductHandle>(m, "Product", "A shape modulus or portal result: a Mesh (3D) or an image (2D)")
      .def_readonly("kind", &ProductHandle::kind, "'ply' (mesh) or 'png' (image)")
      .def_readonly("mesh", &ProductHandle::mesh, "3D: the Mesh (unit frame)")
      .def_readonly("image", &ProductHandle::image, "2D: (H, W, 3) uint8, row 0 at the top")
      .def_readonly("report", &ProductHandle::report, "the command's JSON report");
  m.def("modulus", &ShapeModulus, py::arg("target"), py::kw_only(), py::arg("out") = py::none(),
        "The shape modulus (Schor and Kim 2023; `quijibo modulus`, the experiment's modulus stage) of `target` (a "
        "mesh, a .qgrid or an analytic shape): settings as the experiment's modulus object (alpha=, beta=, "
        "offset=, params=, versor={...}, output={'format': 'ply' or 'png', 'resolution': ..., ...}); with out= "
        "(.ply or .png) also written.");
  m.def("portal", &Portal, py::kw_only(), py::arg("out") = py::none(),
        "Portals (Schor and Kim 2024; `quijibo portal`, the experiment's portal stage): spec= (a file or a dict) "
        "or koch=True, alpha=, output={'format': 'png' or 'ply', ...}; with out= also written.");
  m.def("julia", &JuliaSetOf, py::arg("map"), py::kw_only(), py::arg("out") = py::none(),
        "The Julia set of a map of any kind (`quijibo julia`, the experiment method \"julia\"; docs/map-kinds.md): "
        "map= a map object as a dict ({'kind': 'polynomial', 'c': [...]}, {'kind': 'rational', 'file': ...}) or the "
        "path of a JSON file holding one; output={'format': 'png' or 'ply', 'resolution': ..., 'iterations': ..., "
        "...} (iterations, escape and box default to the kind's); with out= (.ply or .png) also written.");
  m.def("run", &Run, py::arg("experiment"), py::kw_only(), py::arg("out") = py::none(),
        py::arg("resume") = pipeline::RunOptions{}.resume, py::arg("check") = pipeline::RunOptions{}.check_only,
        py::arg("quiet") = pipeline::RunOptions{}.quiet,
        "Run an experiment (`quijibo run`): a JSON file's path or the document as a dict (paths relative to the "
        "working folder), into out= (default: the experiment's outputs.folder, else results/<name>); resume=True "
        "continues an interrupted optimization, check=True only resolves. Returns {'results', 'seconds', "
        "'stages': [{'name', 'status', 'hash', 'seconds'}], 'resolved'}.");

  m.def("optimize", &OptimizeMap, py::arg("target"), py::arg("map"), py::arg("schedule") = py::none(),
        py::arg("callback") = py::none(), py::kw_only(), py::arg("out") = py::none(), py::arg("resume") = false,
        "Optimize `map`'s exponents, ln C, tau and beta on the signed distance Grid `target` (`quijibo optimize`; "
        "the map is not changed). `schedule`: the paper's notation, a dict (the JSON form) or a .json path; other "
        "settings as keywords with the experiment's names (alpha=, evaluator=, weights=, max_iterations={'F': 50}, "
        "...). `callback(record)` gets every record of the run (a dict: the log.jsonl line) and returns True to "
        "stop. `out`: the folder for initial_map.json, map.json, log.jsonl, summary.json and checkpoints (default: "
        "none, nothing is written); resume=True continues the interrupted run there. Returns (map, summary): the best map and "
        "summary.json as a dict ('complete' False and 'stop_reason' when a callback stopped it). Ctrl-C writes a "
        "checkpoint and raises KeyboardInterrupt.");
  m.def("mesh", &Mesh, py::arg("map"), py::arg("resolution") = pipeline::MeshStageOptions{}.meshing.resolution,
        py::arg("iterations") = pipeline::MeshStageOptions{}.julia.iterations, py::kw_only(),
        py::arg("allow_empty") = false,
        "Mesh the Julia set {log|q_n| < iso} of `map` by marching cubes (`quijibo mesh`, the experiment's mesh "
        "stage): resolution cells along the box's longest side, n = iterations map applications. Other settings "
        "as keywords with the experiment's names: escape, iso, frame ('user': the input mesh's coordinates, or "
        "'fractal'), precision, box [xmin, ymin, zmin, xmax, ymax, zmax] (fractal frame; default: the normalized "
        "unit cube), ... An empty set raises quijibo.Error unless allow_empty=True.");
  m.def(
      "render",
      [](const MeshResult& mesh_in, py::kwargs kwargs) {
        // The pictures settings of the experiment (render_size, render_views, render_shading, ...).
        json settings = ToJson(kwargs, "render");
        const pipeline::PicturesOptions o = OptionsFrom<pipeline::PicturesOptions>(settings, "render");
        const mesh::TriangleMesh t = ToTriangleMesh(mesh_in.vertices.cast<Array>(),
                                                    mesh_in.faces.cast<py::array_t<std::int64_t, py::array::c_style |
                                                                                                       py::array::forcecast>>());
        Image image(1, 1);
        {
          py::gil_scoped_release release;
          image = mesh::RenderMesh(t, o.render);
        }
        return ImageArray(image);
      },
      py::arg("mesh"),
      "Render a mesh (`quijibo picture render`): views side by side, ray-traced with ambient occlusion, soft "
      "shadows and a ground (render_shading='flat': the z-buffer and Lambert shading). Settings as keywords with "
      "the experiment's pictures names: render_size (pixels per view), render_views (1-4: front, side, top, "
      "three-quarter), render_shading, render_samples, render_ao_rays. Returns an (H, W, 3) uint8 array.");
}

}  // namespace
}  // namespace quijibo::python

PYBIND11_MODULE(quijibo, m) {
  using namespace quijibo;
  using namespace quijibo::python;
  m.doc() =
      "quijibo: quaternion Julia sets shaped like a mesh (QUIJIBO, Kim 2015), from Python.\n"
      "Maps, grids, the energy, the initial guess, the optimizer and the mesher on NumPy arrays; see "
      "docs/python.md.";
  m.attr("__version__") = QUIJIBO_VERSION;

  // quijibo.Error: the one exception; its message is the line the command line prints.
  static PyObject* error_type =
      PyErr_NewExceptionWithDoc("quijibo.Error",
                                "A quijibo error: the message names the file (and line or JSON pointer) and says "
                                "what was expected, as the command line prints it.",
                                PyExc_Exception, nullptr);
  m.attr("Error") = py::handle(error_type);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyErr_SetString(error_type, e.what());
    } catch (const py::error_already_set&) {
      throw;
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {
      // Library exceptions the command line also prints as errors (JSON, file system).
      PyErr_SetString(error_type, e.what());
    }
  });

  BindFrames(m);
  BindMaps(m);
  BindGrids(m);
  BindEnergy(m);
  BindInitialGuess(m);
  BindMesh(m);
  BindStages(m);
}
