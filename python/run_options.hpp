#pragma once
/// Keyword arguments of `softbake.run()` and `softbake.Simulation()` as the RunOptions that
/// `softbake run` fills from its flags: one keyword per flag, named as the flag without its dashes
/// and with '_' for '-' (--no-pair-cache: no_pair_cache), checked against the same ranges and
/// choices the command line checks.

#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "bake/run_options.hpp"

namespace softbake::python {

/// Which keywords a call takes: Simulation() those that shape the simulation and its loading
/// (and `threads`); run() all of them.
enum class KeywordSet { Simulation, Run };

/// Writes `keywords` into `options`. `caller` ("run()") starts the messages. Throws TypeError
/// for an unknown keyword or a value of the wrong type, ValueError for one the command line would
/// refuse. Returns the flags of `softbake run` that ask for the same, in order: the command a
/// user can paste to resume the run.
std::vector<std::string> applyKeywords(const pybind11::kwargs& keywords, KeywordSet set,
                                       const char* caller, RunOptions& options);

/// The keywords `set` takes, sorted: what the docstrings and the messages list.
std::vector<std::string> keywordNames(KeywordSet set);

}  // namespace softbake::python
