#include "run_options.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>

#include "core/broad_phase/broad_phase.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/text.hpp"
#include "render/frame_renderer.hpp"

namespace py = pybind11;

namespace softbake::python {

namespace {

/// Reads one keyword's value; `caller` and the keyword start every message.
struct Reader {
  const char* caller;
  std::string keyword;
  py::handle value;

  [[noreturn]] void wrongType(std::string_view expected) const {
    throw py::type_error(
        cat(caller, ": ", keyword, ": expected ", expected, ", got ",
            py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>(), " ",
            py::repr(value).cast<std::string>()));
  }
  [[noreturn]] void outOfRange(std::string_view expected) const {
    throw py::value_error(cat(caller, ": ", keyword, ": expected ", expected, ", got ",
                              py::repr(value).cast<std::string>()));
  }

  bool flag() const {
    if (!PyBool_Check(value.ptr())) wrongType("True or False");
    return value.ptr() == Py_True;
  }

  /// A whole number (int, or anything with __index__ such as numpy.int64; not bool) in [low, high].
  long long whole(long long low, long long high) const {
    if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr())) wrongType("a whole number");
    const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
    if (!number) throw py::error_already_set();
    int overflow = 0;
    const long long result = PyLong_AsLongLongAndOverflow(number.ptr(), &overflow);
    if (overflow != 0 || result < low || result > high)
      outOfRange(cat("a whole number from ", low, " to ", high));
    return result;
  }

  /// A finite number (int or float, not bool) in [low, high], or above `low` when `aboveLow`.
  double number(double low, double high, bool aboveLow = false) const {
    if (PyBool_Check(value.ptr()) ||
        !(PyFloat_Check(value.ptr()) || PyIndex_Check(value.ptr()) ||
          py::hasattr(value, "__float__")) ||
        PyUnicode_Check(value.ptr()))
      wrongType("a number");
    const double result = PyFloat_AsDouble(value.ptr());
    if (result == -1.0 && PyErr_Occurred()) throw py::error_already_set();
    if (!std::isfinite(result) || result > high || (aboveLow ? result <= low : result < low)) {
      if (aboveLow && std::isinf(high)) outOfRange(cat("a number above ", low));
      outOfRange(cat("a number from ", low, " to ", high));
    }
    return result;
  }

  std::string text() const {
    if (!PyUnicode_Check(value.ptr())) wrongType("a string");
    return value.cast<std::string>();
  }

  /// A path: str, bytes or os.PathLike, as the file system's text.
  std::string path() const {
    if (!PyUnicode_Check(value.ptr()) && !PyBytes_Check(value.ptr()) &&
        !py::hasattr(value, "__fspath__"))
      wrongType("a path (str or os.PathLike)");
    return py::module_::import("os").attr("fsdecode")(value).cast<std::string>();
  }

  std::string choice(const std::vector<std::string>& names) const {
    const std::string name = text();
    if (std::find(names.begin(), names.end(), name) == names.end())
      outOfRange(alternatives(names, "'"));
    return name;
  }
};

/// Shortest decimal text of `value` that reads back the same: a number in the command line.
std::string numberText(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

/// What one keyword does: writes `options` and appends its flags to `flags`.
using Apply =
    std::function<void(const Reader&, RunOptions& options, std::vector<std::string>& flags)>;

struct Keyword {
  KeywordSet set;  ///< Simulation: taken by both; Run: by run() alone
  Apply apply;
};

/// A presence flag of `softbake run` (--vdb): True sets it, False leaves it off.
Keyword flagKeyword(KeywordSet set, std::string flag, bool RunOptions::*field) {
  return {set, [flag, field](const Reader& r, RunOptions& o, std::vector<std::string>& flags) {
            o.*field = r.flag();
            if (o.*field) flags.push_back(flag);
          }};
}

Keyword loadFlagKeyword(std::string flag, bool SceneLoadOptions::*field) {
  return {KeywordSet::Simulation,
          [flag, field](const Reader& r, RunOptions& o, std::vector<std::string>& flags) {
            o.load.*field = r.flag();
            if (o.load.*field) flags.push_back(flag);
          }};
}

Keyword wholeKeyword(KeywordSet set, std::string flag, int low, int high,
                     std::optional<int> RunOptions::*field) {
  return {set, [=](const Reader& r, RunOptions& o, std::vector<std::string>& flags) {
            o.*field = int(r.whole(low, high));
            flags.insert(flags.end(), {flag, std::to_string(*(o.*field))});
          }};
}

template <class Target>
Keyword loadWholeKeyword(std::string flag, long long low, long long high,
                         Target SceneLoadOptions::*field) {
  return {KeywordSet::Simulation,
          [=](const Reader& r, RunOptions& o, std::vector<std::string>& flags) {
            const long long value = r.whole(low, high);
            o.load.*field = static_cast<std::remove_cvref_t<decltype(o.load.*field)>>(value);
            flags.insert(flags.end(), {flag, std::to_string(value)});
          }};
}

Keyword choiceKeyword(KeywordSet set, std::string flag, std::vector<std::string> names,
                      std::optional<std::string> RunOptions::*field) {
  return {set, [=](const Reader& r, RunOptions& o, std::vector<std::string>& flags) {
            o.*field = r.choice(names);
            flags.insert(flags.end(), {flag, *(o.*field)});
          }};
}

const std::map<std::string, Keyword>& keywords() {
  using S = KeywordSet;
  static const std::map<std::string, Keyword> table = [] {
    std::map<std::string, Keyword> k;
    // What Simulation() takes too: the simulation settings and how the scene is loaded.
    k.emplace("frames", wholeKeyword(S::Simulation, "--frames", 1, 10000000, &RunOptions::frames));
    k.emplace("fps", Keyword{S::Simulation, [](const Reader& r, RunOptions& o, auto& flags) {
                               o.fps = r.number(0.001, 1e6);
                               flags.insert(flags.end(), {"--fps", numberText(*o.fps)});
                             }});
    k.emplace("integrator", choiceKeyword(S::Simulation, "--integrator", integratorNames(),
                                          &RunOptions::integrator));
    k.emplace("substeps", Keyword{S::Simulation, [](const Reader& r, RunOptions& o, auto& flags) {
                                    if (PyUnicode_Check(r.value.ptr()) && r.text() == "auto")
                                      o.substeps = "auto";
                                    else if (PyUnicode_Check(r.value.ptr()))
                                      r.outOfRange("'auto' or a whole number >= 1");
                                    else
                                      o.substeps = std::to_string(r.whole(1, 1 << 30));
                                    flags.insert(flags.end(), {"--substeps", *o.substeps});
                                  }});
    k.emplace("broadphase", choiceKeyword(S::Simulation, "--broadphase", broadPhaseNames(),
                                          &RunOptions::broadPhase));
    k.emplace("levels", wholeKeyword(S::Simulation, "--levels", 0, 8, &RunOptions::levels));
    k.emplace("response", choiceKeyword(S::Simulation, "--response", responseModeNames(),
                                        &RunOptions::response));
    k.emplace("no_response", flagKeyword(S::Simulation, "--no-response", &RunOptions::noResponse));
    k.emplace("no_pair_cache",
              flagKeyword(S::Simulation, "--no-pair-cache", &RunOptions::noPairCache));
    k.emplace("threads",
              Keyword{S::Simulation, [](const Reader& r, RunOptions& o, auto& flags) {
                        o.threads = int(r.whole(0, 4096));
                        flags.insert(flags.end(), {"--threads", std::to_string(o.threads)});
                      }});
    k.emplace("accept_lossy_import",
              loadFlagKeyword("--accept-lossy-import", &SceneLoadOptions::acceptLossyImport));
    k.emplace("max_vertices",
              loadWholeKeyword("--max-vertices", 1, 1LL << 62, &SceneLoadOptions::maxVertices));
    k.emplace("max_faces",
              loadWholeKeyword("--max-faces", 1, 1LL << 62, &SceneLoadOptions::maxFaces));
    k.emplace("max_import_memory", loadWholeKeyword("--max-import-memory", 1, 1LL << 40,
                                                    &SceneLoadOptions::maxImportMemoryMib));
    k.emplace("max_import_seconds",
              loadWholeKeyword("--max-import-seconds", 1, static_cast<long long>(kMaxImportSeconds),
                               &SceneLoadOptions::maxImportSeconds));
    k.emplace("max_bodies",
              loadWholeKeyword("--max-bodies", 1, 1LL << 40, &SceneLoadOptions::maxBodies));

    // run() alone: the outputs.
    k.emplace("frame_padding",
              wholeKeyword(S::Run, "--frame-padding", 1, 9, &RunOptions::framePadding));
    k.emplace("contacts", flagKeyword(S::Run, "--contacts", &RunOptions::contacts));
    k.emplace("render", Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                                  if (r.value.is_none()) return;  // the scene's choice
                                  o.render = r.flag();
                                  flags.push_back(*o.render ? "--render" : "--no-render");
                                }});
    k.emplace("size",
              Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                        // "1280x720", or (1280, 720); run() checks the bounds as the
                        // command does.
                        if (PyTuple_Check(r.value.ptr()) || PyList_Check(r.value.ptr())) {
                          const py::sequence pair = py::reinterpret_borrow<py::sequence>(r.value);
                          if (pair.size() != 2) r.wrongType("'WIDTHxHEIGHT' or (width, height)");
                          const py::object first = pair[0], second = pair[1];
                          const Reader width{r.caller, r.keyword + "[0]", first};
                          const Reader height{r.caller, r.keyword + "[1]", second};
                          o.size = cat(width.whole(16, 16384), "x", height.whole(16, 16384));
                        } else {
                          o.size = r.text();
                        }
                        flags.insert(flags.end(), {"--size", *o.size});
                      }});
    k.emplace("no_contact_spheres",
              flagKeyword(S::Run, "--no-contact-spheres", &RunOptions::noContactSpheres));
    k.emplace("contacts_view", choiceKeyword(S::Run, "--contacts-view", contactsViewNames(),
                                             &RunOptions::contactsView));
    k.emplace("render_while_simulating",
              flagKeyword(S::Run, "--render-while-simulating", &RunOptions::renderWhileSimulating));
    k.emplace("pc2", flagKeyword(S::Run, "--pc2", &RunOptions::pc2));
    k.emplace("mdd", flagKeyword(S::Run, "--mdd", &RunOptions::mdd));
    k.emplace("vdb", flagKeyword(S::Run, "--vdb", &RunOptions::vdb));
    k.emplace("voxel_size",
              Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                        o.voxelSize = r.number(0, HUGE_VAL, true);
                        flags.insert(flags.end(), {"--voxel-size", numberText(*o.voxelSize)});
                      }});
    k.emplace("vdb_fog", flagKeyword(S::Run, "--vdb-fog", &RunOptions::vdbFog));
    k.emplace("vdb_compression",
              choiceKeyword(S::Run, "--vdb-compression", {"zip", "blosc", "none"},
                            &RunOptions::vdbCompression));
    k.emplace("up", choiceKeyword(S::Run, "--up", {"y", "z"}, &RunOptions::upAxis));
    k.emplace("quiet", flagKeyword(S::Run, "--quiet", &RunOptions::quiet));
    k.emplace("max_output_gib",
              Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                        o.maxOutputGib = r.number(0, HUGE_VAL, true);
                        flags.insert(flags.end(), {"--max-output-gib", numberText(o.maxOutputGib)});
                      }});
    k.emplace("no_cache", Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                                    o.cache = !r.flag();
                                    if (!o.cache) flags.push_back("--no-cache");
                                  }});
    k.emplace("checkpoint_every", wholeKeyword(S::Run, "--checkpoint-every", 1, 10000000,
                                               &RunOptions::checkpointEvery));
    k.emplace("cache_only", flagKeyword(S::Run, "--cache-only", &RunOptions::cacheOnly));
    k.emplace("resume", flagKeyword(S::Run, "--resume", &RunOptions::resume));
    k.emplace("report", Keyword{S::Run, [](const Reader& r, RunOptions& o, auto& flags) {
                                  o.report = r.path();
                                  flags.insert(flags.end(), {"--report", o.report->string()});
                                }});
    return k;
  }();
  return table;
}

}  // namespace

std::vector<std::string> keywordNames(KeywordSet set) {
  std::vector<std::string> names;
  for (const auto& [name, keyword] : keywords())
    if (set == KeywordSet::Run || keyword.set == KeywordSet::Simulation) names.push_back(name);
  return names;
}

std::vector<std::string> applyKeywords(const py::kwargs& given, KeywordSet set, const char* caller,
                                       RunOptions& options) {
  std::vector<std::string> flags;
  for (const auto& [key, value] : given) {
    const std::string name = py::str(key).cast<std::string>();
    const auto found = keywords().find(name);
    if (found == keywords().end() ||
        (set == KeywordSet::Simulation && found->second.set != KeywordSet::Simulation))
      throw py::type_error(cat(caller, " got an unexpected keyword argument '", name,
                               "'; it takes ", alternatives(keywordNames(set), "'")));
    found->second.apply(Reader{caller, name, value}, options, flags);
  }
  // The command line's exclusions.
  if (!options.cache && given.contains("checkpoint_every"))
    throw py::value_error(cat(caller, ": checkpoint_every excludes no_cache"));
  if (!options.cache && options.cacheOnly)
    throw py::value_error(cat(caller, ": cache_only excludes no_cache"));
  return flags;
}

}  // namespace softbake::python
