// The Python module `softbake`: a scene simulated frame by frame in the interpreter
// (Simulation), the whole `softbake run` (run()), and softbake.Error for what the command line
// reports as "softbake: error: …".
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include "bake/interruption.hpp"
#include "bake/run_bake.hpp"
#include "bake/scene_input.hpp"
#include "bake/shell_quote.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "importers/bench_scenes.hpp"
#include "importers/scene_file.hpp"
#include "output/version.hpp"
#include "run_options.hpp"
#include "stderr_tail.hpp"

namespace py = pybind11;

namespace softbake::python {

// positions() and velocities() hand NumPy a view of the simulator's own std::vector<Vec3>: a body
// is a run of particles, each three Scalars with nothing between them, so (N, 3) with strides
// (sizeof(Vec3), sizeof(Scalar)) is exactly its memory. Float in the default build: float32.
static_assert(sizeof(Vec3) == 3 * sizeof(Scalar) && alignof(Vec3) == alignof(Scalar),
              "Vec3 must be three packed Scalars for the zero-copy arrays");
#ifndef SOFTBAKE_DOUBLE_PRECISION
static_assert(std::is_same_v<Scalar, float> && sizeof(Vec3) == 12,
              "the default build's positions are float32 triples");
#endif

namespace {

/// The source a scene given as a dict is named by in messages ("scene dict: bodies[0].mass: …")
/// and, unless it has a "name", the scene's name.
constexpr const char* kDictSource = "scene dict";

/// `value` as JSON, with `path` ("bodies[0].material") naming where it sits in messages. Takes
/// what json.dumps takes, and NumPy scalars and arrays.
nlohmann::json toJson(py::handle value, const std::string& path) {
  const auto where = [&] { return cat(kDictSource, path.empty() ? "" : ": ", path); };
  PyObject* object = value.ptr();
  if (object == Py_None) return nullptr;
  if (PyBool_Check(object)) return object == Py_True;
  if (PyUnicode_Check(object)) return value.cast<std::string>();
  if (PyFloat_Check(object)) {
    const double number = PyFloat_AsDouble(object);
    if (!std::isfinite(number))
      throw py::value_error(cat(where(), ": ", number, " is not a JSON number"));
    return number;
  }
  if (py::hasattr(value, "tolist") && py::hasattr(value, "dtype"))  // NumPy arrays and scalars
    return toJson(value.attr("tolist")(), path);
  if (PyIndex_Check(object)) {
    const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(object));
    if (!number) throw py::error_already_set();
    int overflow = 0;
    const long long whole = PyLong_AsLongLongAndOverflow(number.ptr(), &overflow);
    if (overflow == 0) return whole;
    const unsigned long long big = PyLong_AsUnsignedLongLong(number.ptr());
    if (!PyErr_Occurred()) return big;
    PyErr_Clear();
    throw py::value_error(
        cat(where(), ": ", py::str(value).cast<std::string>(), " is out of range for JSON"));
  }
  if (PyDict_Check(object)) {
    nlohmann::json result = nlohmann::json::object();
    for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(value)) {
      if (!PyUnicode_Check(key.ptr()))
        throw py::type_error(
            cat(where(), ": the key ", py::repr(key).cast<std::string>(), " is not a string"));
      const std::string name = key.cast<std::string>();
      result[name] = toJson(item, path.empty() ? name : cat(path, ".", name));
    }
    return result;
  }
  if (PyList_Check(object) || PyTuple_Check(object)) {
    nlohmann::json result = nlohmann::json::array();
    std::size_t index = 0;
    for (py::handle item : value) result.push_back(toJson(item, cat(path, "[", index++, "]")));
    return result;
  }
  throw py::type_error(cat(where(), ": ",
                           py::type::handle_of(value).attr("__name__").cast<std::string>(),
                           " is not JSON (expected dict, list, str, int, float, bool or None)"));
}

/// "a, b, c": the names in a docstring.
std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

/// A path given as str, bytes or os.PathLike, as the file system's text.
std::string pathText(py::handle path) {
  return py::module_::import("os").attr("fsdecode")(path).cast<std::string>();
}

/// Runs `work` in `arena` when there is one (a thread limit), else on TBB's default arena.
template <class Work>
void inArena(const std::unique_ptr<tbb::task_arena>& arena, Work&& work) {
  if (arena)
    arena->execute(work);
  else
    work();
}

class Simulation {
 public:
  /// Loads `scene` (a path or built-in name, or nullopt for the built-in default scene) or
  /// `json` (a scene dict), applies `options`, and builds the simulator. Called without the GIL.
  Simulation(const std::optional<std::string>& scene, const std::optional<nlohmann::json>& json,
             const RunOptions& options) {
    if (options.threads > 0) arena_ = std::make_unique<tbb::task_arena>(options.threads);
    SceneFile file =
        json ? parseScene(*json, kDictSource, std::filesystem::current_path(), options.load)
             : loadSceneInput(scene.value_or(""), options.load);
    applySceneOptions(options.given, file);
    name_ = file.setup.name;
    notes_ = std::move(file.notes);
    warnings_ = std::move(file.warnings);
    inArena(arena_, [&] {
      BuildReport report;
      simulator_ = std::make_unique<Simulator>(buildSceneTopology(file.setup, &report));
      notes_.insert(notes_.end(), report.notes.begin(), report.notes.end());
    });
    const SceneTopology& topology = simulator_->topology();
    for (const Body& body : topology.bodies) bodyNames_.push_back(body.name);
    for (Index surface = 0; surface < topology.surfaceCount(); ++surface)
      surfaceFirstTriangle_.push_back(topology.surfaceFirstTriangle(surface));
  }

  /// Simulates `frames` more frames, without the GIL; a pending KeyboardInterrupt (or another
  /// signal Python handles) stops it between two frames.
  void advance(int frames) {
    if (frames < 0) throw py::value_error(cat("advance(): frames must be 0 or more, got ", frames));
    if (!failure_.empty()) throw Error(failure_);
    const Busy busy(*this, "advance()");
    py::gil_scoped_release release;
    for (int i = 0; i < frames; ++i) {
      try {
        inArena(arena_, [&] { simulator_->advanceToFrame(frame_ + 1); });
      } catch (const Error& error) {
        failure_ = error.what();  // the state is half a frame on: nothing more can follow
        throw;
      }
      ++frame_;
      if (i + 1 < frames) {
        py::gil_scoped_acquire acquire;
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      }
    }
  }

  int frame() const { return frame_; }
  const std::string& name() const { return name_; }
  const std::vector<std::string>& bodies() const { return bodyNames_; }
  const std::vector<std::string>& notes() const { return notes_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  const SceneTopology& topology() const { return simulator_->topology(); }
  const Simulator& simulator() const { return *simulator_; }

  /// The body named or numbered (negative from the end) by `body`.
  const Body& body(py::handle body) const {
    const std::vector<Body>& bodies = topology().bodies;
    if (PyUnicode_Check(body.ptr())) {
      const std::string name = body.cast<std::string>();
      for (const Body& candidate : bodies)
        if (candidate.name == name) return candidate;
      std::string names;
      for (const std::string& known : bodyNames_)
        names += cat(names.empty() ? "" : ", ", "'", known, "'");
      throw py::key_error(
          cat("no body '", name, "' in scene '", name_, "' (its bodies: ", names, ")"));
    }
    if (PyBool_Check(body.ptr()) || !PyIndex_Check(body.ptr()))
      throw py::type_error("body: expected a body's name (str) or index (int)");
    const long long count = static_cast<long long>(bodies.size());
    const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(body.ptr()));
    if (!number) throw py::error_already_set();
    int overflow = 0;
    long long index = PyLong_AsLongLongAndOverflow(number.ptr(), &overflow);
    if (overflow != 0 || index < -count || index >= count)
      throw py::index_error(cat("body ", py::repr(number).cast<std::string>(), ": scene '", name_,
                                "' has ", count, " bodies"));
    if (index < 0) index += count;
    return bodies[std::size_t(index)];
  }

  /// The contacts of the latest frame as the contacts JSON writer lists them.
  py::list contacts() const {
    const Busy busy(*this, "contacts()");
    const SceneTopology& topology = this->topology();
    const auto triple = [](const Vec3& v) {
      return py::make_tuple(double(v.x()), double(v.y()), double(v.z()));
    };
    const auto local = [&](Index triangle, Index surface) -> py::object {
      if (triangle == kNoIndex) return py::none();
      return py::int_(triangle - surfaceFirstTriangle_[surface]);
    };
    py::list list;
    for (const Contact& c : simulator_->contacts()) {
      py::dict contact;
      contact["kind"] = std::string(contactKindName(c.kind));
      contact["position"] = triple(c.position);
      contact["normal"] = triple(c.normal);
      contact["bodies"] =
          py::make_tuple(topology.surfaceName(c.surfaceA), contactPartnerName(topology, c));
      contact["triangles"] =
          py::make_tuple(local(c.triangleA, c.surfaceA), local(c.triangleB, c.surfaceB));
      contact["particle"] =
          c.particle == kNoIndex
              ? py::object(py::none())
              : py::object(py::int_(c.particle - topology.bodies[c.surfaceA].firstParticle));
      list.append(std::move(contact));
    }
    return list;
  }

 private:
  /// Marks the simulation in use by a call that must not overlap advance(), which runs without
  /// the GIL while other Python threads may call in.
  class Busy {
   public:
    Busy(const Simulation& simulation, const char* call) : busy_(simulation.busy_) {
      if (busy_.exchange(true))
        throw py::value_error(
            cat(call, ": advance() is running on this Simulation in another thread"));
    }
    ~Busy() { busy_ = false; }

   private:
    std::atomic<bool>& busy_;
  };

  std::unique_ptr<tbb::task_arena> arena_;  ///< set when `threads` limits the worker threads
  std::unique_ptr<Simulator> simulator_;
  std::string name_;
  std::vector<std::string> bodyNames_, notes_, warnings_;
  std::vector<Index> surfaceFirstTriangle_;
  int frame_ = 1;  ///< frame 1 is the initial state, as in the outputs
  std::string failure_;
  mutable std::atomic<bool> busy_{false};
};

/// positions() or velocities(): a read-only (N, 3) view of `body`'s run of `vectors`, whose base
/// is the Simulation, so it stays alive as long as the array does.
py::array bodyView(py::object self, py::handle body, bool velocities) {
  const Simulation& simulation = self.cast<const Simulation&>();
  const Body& b = simulation.body(body);
  const SimulationState& state = simulation.simulator().state();
  const Vec3* first = (velocities ? state.velocity : state.position).data() + b.firstParticle;
  py::array view(py::dtype::of<Scalar>(), {py::ssize_t(b.particleCount), py::ssize_t(3)},
                 {py::ssize_t(sizeof(Vec3)), py::ssize_t(sizeof(Scalar))}, first->data(), self);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

/// softbake.Error, once the module has made it.
PyObject* errorClass = nullptr;

/// One `softbake.run()` at a time: runBake() installs process-wide signal handlers and the
/// error capture redirects the process's stderr.
std::mutex runMutex;

int run(py::object scene, py::object out, py::kwargs keywords) {
  RunOptions options;
  if (!scene.is_none()) {
    if (PyDict_Check(scene.ptr()))
      throw py::type_error(
          "run(): scene must be a path or a built-in scene name; write a scene dict to a .json "
          "file first (its mesh paths are relative to the file)");
    options.input = pathText(scene);
  }
  options.out = pathText(out);
  const std::vector<std::string> flags = applyKeywords(keywords, KeywordSet::Run, "run()", options);
  // The command that does the same, printed with --resume when the run is interrupted.
  std::vector<std::string> words{"softbake", "run"};
  if (!options.input.empty()) words.push_back(options.input);
  words.insert(words.end(), {"--out", options.out.string()});
  words.insert(words.end(), flags.begin(), flags.end());
  for (const std::string& word : words)
    options.commandLine.append(options.commandLine.empty() ? "" : " ").append(shellQuoted(word));

  int code = 0;
  std::string reported;
  {
    py::gil_scoped_release release;
    const std::lock_guard lock(runMutex);
    std::fflush(stdout);
    StderrTail stderrTail;
    code = runBake(options);
    std::fflush(stdout);
    reported = reportedError(stderrTail.finish());
  }
  // Interrupted runs return their status like a finished one: they are resumable, not failed.
  if (code == 0 || code == interruptedExitCode(SIGINT) || code == interruptedExitCode(SIGTERM))
    return code;
  const py::object error = py::reinterpret_borrow<py::object>(errorClass)(
      reported.empty() ? cat("softbake run failed (exit code ", code, ")") : reported);
  error.attr("exit_code") = code;
  PyErr_SetObject(errorClass, error.ptr());
  throw py::error_already_set();
}

}  // namespace

}  // namespace softbake::python

PYBIND11_MODULE(softbake, m) {
  using namespace softbake;
  using namespace softbake::python;
  m.doc() =
      "softbake: offline soft-body simulation (pressure soft bodies, Mesit & Guha's "
      "collisions).\n\n"
      "Simulation(scene) simulates a scene frame by frame in this process; run(scene, out) does "
      "all that `softbake run` does. Errors raise softbake.Error with the message the command "
      "prints.";
  m.attr("__version__") = softbakeVersion();

  // softbake::Error and file-system errors are what the command reports as "softbake: error: …";
  // both raise softbake.Error with that message.
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  error.doc() =
      "What `softbake` reports as 'softbake: error: MESSAGE': str(e) is MESSAGE. Raised by "
      "run(), it has exit_code, the status the command exits with.";
  error.attr("exit_code") = py::none();
  errorClass = error.ptr();
  py::register_exception_translator([](std::exception_ptr pending) {
    try {
      if (pending) std::rethrow_exception(pending);
    } catch (const Error& e) {
      error(e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      error(e.what());
    }
  });

  m.def("builtin_scenes", &benchSceneNames,
        "The built-in scene names Simulation() and run() take: default, balls1k, balls10k, ...");

  // The keywords are the option table's (importers/option_table.hpp), listed from it; pybind11
  // keeps the docstrings' pointers, so the texts live as long as the module.
  static const std::string simulationDoc = cat(R"doc(
A scene simulated frame by frame, as `softbake run` simulates it.

Simulation(scene=None, **options)
  scene: a scene .json, a mesh file (any format assimp reads; dropped on the ground as a soft
    body), a built-in scene name (softbake.builtin_scenes()), a dict holding a scene's JSON (mesh
    paths relative to the current directory), or None for the built-in default scene.
  options: the simulation settings `softbake run` takes as flags, named as the flag without its
    dashes and with '_' for '-': )doc",
                                               joined(keywordNames(KeywordSet::Simulation)), R"doc(.
    threads limits the worker threads (0: all cores). The results do not depend on it.

The simulation starts at frame 1, the initial state; advance() simulates the next frames.
)doc");
  py::class_<Simulation>(m, "Simulation", simulationDoc.c_str())
      .def(py::init([](py::object scene, py::kwargs keywords) {
             RunOptions options;
             applyKeywords(keywords, KeywordSet::Simulation, "Simulation()", options);
             std::optional<std::string> path;
             std::optional<nlohmann::json> json;
             if (PyDict_Check(scene.ptr()))
               json = toJson(scene, "");
             else if (!scene.is_none())
               path = pathText(scene);
             py::gil_scoped_release release;  // meshes load and the topology builds meanwhile
             return std::make_unique<Simulation>(path, json, options);
           }),
           py::arg("scene") = py::none())
      .def("advance", &Simulation::advance, py::arg("frames") = 1, R"doc(
Simulates `frames` more frames (Simulator::advanceToFrame for each), without holding the GIL.
A blow-up raises softbake.Error, naming the body and frame as the command does; the simulation
cannot go on after it. Ctrl-C (KeyboardInterrupt) stops it between two frames.
)doc")
      .def_property_readonly(
          "frame", &Simulation::frame,
          "The frame the state is at: 1 is the initial state, as in the outputs.")
      .def_property_readonly(
          "frames", [](const Simulation& s) { return s.topology().settings.frames; },
          "The frames the scene asks for (settings.frames, or frames=).")
      .def_property_readonly("fps", [](const Simulation& s) { return s.topology().settings.fps; })
      .def_property_readonly(
          "time", [](const Simulation& s) { return (s.frame() - 1) / s.topology().settings.fps; },
          "Seconds since frame 1.")
      .def_property_readonly("name", &Simulation::name,
                             "The scene's name, as the output files have it.")
      .def_property_readonly("bodies", &Simulation::bodies, "The soft bodies' names, in order.")
      .def_property_readonly("notes", &Simulation::notes,
                             "What loading and building the scene did that `run` prints as notes.")
      .def_property_readonly("warnings", &Simulation::warnings,
                             "What may be wrong with the meshes, as `run` prints it.")
      .def_property_readonly(
          "substeps", [](const Simulation& s) { return s.simulator().substeps().substeps; },
          "Substeps of the latest frame.")
      .def(
          "positions", [](py::object self, py::handle body) { return bodyView(self, body, false); },
          py::arg("body"), R"doc(
The positions of `body` (its name, or its index in `bodies`) as a read-only (N, 3) array of
float32 (float64 in a SOFTBAKE_DOUBLE_PRECISION build), in particle order: the order of the
body's `v` lines in the OBJ frames. No copy: the array is a view of the simulation's own state,
so it changes when advance() runs (copy it to keep a frame), and it keeps the Simulation alive.
)doc")
      .def(
          "velocities", [](py::object self, py::handle body) { return bodyView(self, body, true); },
          py::arg("body"), "The velocities of `body` (m/s), a view like positions().")
      .def("contacts", &Simulation::contacts, R"doc(
The contacts of the latest frame's last substep, as the contacts JSON files list them: a list of
dicts with kind ('edge-triangle', 'particle-triangle', 'corner' or 'plane'), position and normal
(x, y, z), bodies (the two surfaces' names), triangles (each surface's own triangle index, or
None) and particle (the crossing particle's index in its body, or None).
)doc")
      .def("__repr__", [](const Simulation& s) {
        return cat("<softbake.Simulation '", s.name(), "' at frame ", s.frame(), " of ",
                   s.topology().settings.frames, ", ", s.bodies().size(), " bodies>");
      });

  static const std::string runDoc = cat(R"doc(
Does what `softbake run SCENE --out OUT ...` does, in this process: simulates the scene and writes
its outputs (OBJ, PNG, VDB, contacts, the simulation cache and the manifest) as the command does,
printing what it prints, without holding the GIL.

scene: a scene .json, a mesh file or a built-in scene name; None for the built-in default scene.
out: the output folder.
options: the flags of `softbake run`, named without their dashes and with '_' for '-': )doc",
                                        joined(keywordNames(KeywordSet::Run)), R"doc(.
  render is True (--render), False (--no-render) or None (the scene's choice); substeps 'auto' or
  a count; size '1280x720' or (1280, 720); report a folder (the bake report). None leaves any
  option to the scene.

Returns the command's exit code: 0, or 130/143 when SIGINT/SIGTERM stopped it after a frame (the
run can be continued with resume=True). Raises softbake.Error with the command's message when it
fails, its exit_code the command's status; TypeError/ValueError for options the command line
would refuse.
)doc");
  m.def("run", &run, py::arg("scene") = py::none(), py::arg("out") = "out", runDoc.c_str());
}
