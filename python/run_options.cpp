#include "run_options.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/text.hpp"

namespace py = pybind11;

namespace softbake::python {

namespace {

/// Whether a call of `set` takes `spec`: Simulation() those that shape the simulation and its
/// loading, run() every option of `softbake run` but a negation (--no-render is render=False).
bool takes(KeywordSet set, const OptionSpec& spec) {
  if (set == KeywordSet::Simulation) return (spec.commands & kOptionSimulation) != 0;
  return (spec.commands & kOptionRun) != 0 && !isNegation(spec);
}

/// A keyword's value as the JSON value the option table takes; a value of no such type becomes
/// null, which the table's check refuses as a wrong type.
nlohmann::json jsonOf(const OptionSpec& spec, py::handle value) {
  PyObject* object = value.ptr();
  if (PyBool_Check(object)) return object == Py_True;
  if (PyIndex_Check(object)) {
    const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(object));
    if (!number) throw py::error_already_set();
    int overflow = 0;
    const long long whole = PyLong_AsLongLongAndOverflow(number.ptr(), &overflow);
    if (overflow != 0) return overflow > 0 ? HUGE_VAL : -HUGE_VAL;  // out of every range
    return whole;
  }
  if (PyUnicode_Check(object)) {
    const std::string text = value.cast<std::string>();
    return spec.kind == OptionKind::ImageSize ? optionValueFromText(spec, text)
                                              : nlohmann::json(text);
  }
  if (spec.kind == OptionKind::Path && (PyBytes_Check(object) || py::hasattr(value, "__fspath__")))
    return py::module_::import("os").attr("fsdecode")(value).cast<std::string>();
  if (PyFloat_Check(object) || py::hasattr(value, "__float__")) {
    const double number = PyFloat_AsDouble(object);
    if (number == -1.0 && PyErr_Occurred()) throw py::error_already_set();
    return number;
  }
  if (PyTuple_Check(object) || PyList_Check(object)) {
    nlohmann::json array = nlohmann::json::array();
    for (py::handle element : py::reinterpret_borrow<py::sequence>(value))
      array.push_back(jsonOf(spec, element));
    return array;
  }
  return nullptr;
}

}  // namespace

std::vector<std::string> keywordNames(KeywordSet set) {
  std::vector<std::string> names;
  for (const OptionSpec& spec : optionTable())
    if (takes(set, spec)) names.push_back(spec.keyword());
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> applyKeywords(const py::kwargs& given, KeywordSet set, const char* caller,
                                       RunOptions& options) {
  for (const auto& [key, value] : given) {
    const std::string name = py::str(key).cast<std::string>();
    const auto spec = std::find_if(optionTable().begin(), optionTable().end(),
                                   [&](const OptionSpec& s) { return s.keyword() == name; });
    if (spec == optionTable().end() || !takes(set, *spec))
      throw py::type_error(cat(caller, " got an unexpected keyword argument '", name,
                               "'; it takes ", alternatives(keywordNames(set), "'")));
    if (value.is_none()) continue;  // the scene's choice
    const nlohmann::json json = jsonOf(*spec, value);
    if (auto error = checkOptionValue(*spec, json)) {
      const std::string message = cat(caller, ": ", name, ": ", error->message, ", got ",
                                      py::repr(value).cast<std::string>());
      if (error->wrongType) throw py::type_error(message);
      throw py::value_error(message);
    }
    if (spec->kind != OptionKind::Flag || json == true)
      options.given[std::string(spec->name)] = json;
    else if (const OptionSpec* negation = negationOf(*spec))
      options.given[std::string(negation->name)] = true;  // render=False: --no-render
  }
  for (const OptionSpec& spec : optionTable())
    if (options.given.contains(std::string(spec.name)) &&
        options.given.contains(std::string(spec.excludes)))
      throw py::value_error(
          cat(caller, ": ", spec.keyword(), " excludes ", optionSpec(spec.excludes).keyword()));
  landRunOptions(options);
  // The flags that ask for the same, in the table's order.
  std::vector<std::string> flags;
  for (const OptionSpec& spec : optionTable())
    if (const auto found = options.given.find(std::string(spec.name)); found != options.given.end())
      for (std::string& word : optionWords(spec, *found)) flags.push_back(std::move(word));
  return flags;
}

}  // namespace softbake::python
