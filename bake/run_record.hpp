#pragma once
/// What a run was made from and with, as its manifest records it under "run": the input, the
/// SHA-256 of every file loading read, and every option that shapes the outputs. `--resume`
/// compares it with the command it is given; `export` rebuilds the run's writers from it.
///
///   "run": {"input": "/abs/scene.json",
///           "files": [{"path": "/abs/scene.json", "sha256": "…"}, {"path": "/abs/ball.obj", …}],
///           "options": {"frames": 48, "fps": null, …, "checkpoint_every": 17}}
///
/// Options left to the scene are null. The thread count, -q, the output budget and --report are
/// not recorded: they change nothing in the files (a resumed run may add or drop --report).

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bake/run_options.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

/// The record of a run of `options` on `scene` (as loaded), checkpointing every `checkpointEvery`
/// frames (0: no cache).
nlohmann::ordered_json runRecord(const RunOptions& options, const SceneFile& scene,
                                 int checkpointEvery);

/// What differs between a run recorded `before` and the one recorded `now`, one phrase each:
/// "the mesh file '/abs/ball.obj' changed (SHA-256 1f2e… then, 9a8b… now)", "--frames: 48 then,
/// 60 now". Empty when they match.
std::vector<std::string> runRecordDifferences(const nlohmann::ordered_json& before,
                                              const nlohmann::ordered_json& now);

/// `differences` as an error message lists them: each on a line of its own, indented.
std::string listedDifferences(const std::vector<std::string>& differences);

/// The options a recorded run was made with, its input and output folder included, for commands
/// that rebuild its writers. Throws softbake::Error naming `source` for a record it cannot read.
RunOptions runOptionsFromRecord(const nlohmann::ordered_json& record,
                                const std::filesystem::path& outputDirectory,
                                std::string_view source);

/// The checkpoint interval the record names; 0 when the run kept no cache.
int recordedCheckpointInterval(const nlohmann::ordered_json& record);

}  // namespace softbake
