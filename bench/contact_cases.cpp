// The hard contact cases (issue: contacts that hold in the hard cases), measured frame by frame:
// intersecting triangle pairs by the tests' exact checker, contacts and the response's cost per
// substep (the response and the failsafe), energy above the start, and whether the run reached its
// last frame. One markdown table row per scene: bench/contacts.sh writes bench/results/contacts.md
// from them.
//
//   contact_cases SCENE.json|MESH_FILE [explicit|implicit|xpbd] [set_aside|separate|ignore]
//                 [failsafe|nofailsafe] [instep|afterstep] [--csv=FILE] [--frames=N]
//                 [--deep=MICRONS] [--stage-energy]
//   contact_cases --header     the table's header, two lines, for the scripts that print rows
//
// A mesh file is baked as `softbake run FILE` bakes it; --frames=N overrides the scene's frames.
//
// instep keeps the contacts apart within the implicit solve (collisions.contactsInStep).
//
// --csv=FILE appends one row per frame to FILE (scene, variant, frame, intersecting pairs between
// bodies and within one, contacts per substep, energy above the start in J, the new pairs, and
// the bodies the failsafe's last resort put back where their substep started, at rest: bodies
// stopped dead, however clean the frame), with a header when FILE is new: what
// bench/plot_bench.py contacts draws.
//
// New pairs: the intersecting triangle pairs of a frame that did not intersect at the start (what
// the scene placed overlapping is set aside, and its pairs may slide), and of those the ones
// between two surfaces, or within one, that had no intersecting pair at all at the start: a
// crossing where nothing overlapped. The row and the csv give how deep the deepest of those reaches
// (test::penetrationDepth: how far one triangle must move to part them; the row in µm, the csv
// in scene units). Of those again, the ones whose triangles stood apart at the start by more than
// the rounding of their coordinates (test::touchingWithinRounding): faces modelled onto each other
// come out of a float mesh a float step to one side or the other, apart by the exact checker, and
// any motion may round them across; the pairs that stood further apart crossed a real gap.
//
// --deep=MICRONS names on stderr, at each frame's end, every new pair where none overlapped that
// is deeper than MICRONS: its triangles, their surfaces, its depth, how many edges of each go
// through the other (two of one: a corner through a face; one of each: edge against edge), how
// far apart they started, and whether the simulator took it for fitted (closer than the skin at
// the start) and its surfaces for overlapping at the start (its own test, which counts touching
// within rounding; the exact checker's "none overlapped" does not). What the engine's deep pairs
// were traced by, sessions running, with a temporary print.
//
// --stage-energy prints on stderr, at each frame's end, the energy each stage of the substep added
// over the frame (Simulator::measureStageEnergy): which stage makes a gain, where the rest take
// it out again. It costs a whole energy sum per stage of every substep.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>

#include "core/collision/initial_overlap.hpp"
#include "core/dynamics/energy.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "importers/scene_file.hpp"
#include "tests/support/intersection_checker.hpp"

using namespace softbake;

namespace {

void printHeader() {
  std::printf(
      "| scene | integrator | bodies | faces | last frame | intersecting pairs between bodies, max "
      "| within a body, max | contacts/substep | response + failsafe ms/substep | energy above "
      "start, J | frames/s | substeps/frame | new pairs, max | new where none overlapped, max | "
      "the deepest of those, µm | of those, apart at the start past rounding, max | the deepest "
      "of those, µm |\n"
      "|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--header") == 0) {
    printHeader();
    return 0;
  }
  if (argc < 2) {
    std::fprintf(
        stderr,
        "usage: contact_cases SCENE.json|MESH_FILE [explicit|implicit|xpbd] "
        "[set_aside|separate|ignore] [failsafe|nofailsafe] [instep|afterstep] [--csv=FILE] "
        "[--frames=N] [--deep=MICRONS] [--stage-energy]\n       contact_cases --header\n");
    return 1;
  }
  std::FILE* csv = nullptr;
  int frames = 0;
  // The flags anywhere after the scene: taken out, the positional arguments close up.
  const char* csvPath = nullptr;
  double deepMicrons = -1;
  bool stageEnergy = false;
  int kept = 2;
  for (int i = 2; i < argc; ++i) {
    if (std::strncmp(argv[i], "--frames=", 9) == 0)
      frames = std::atoi(argv[i] + 9);
    else if (std::strncmp(argv[i], "--csv=", 6) == 0)
      csvPath = argv[i] + 6;
    else if (std::strncmp(argv[i], "--deep=", 7) == 0)
      deepMicrons = std::atof(argv[i] + 7);
    else if (std::strcmp(argv[i], "--stage-energy") == 0)
      stageEnergy = true;
    else
      argv[kept++] = argv[i];
  }
  argc = kept;
  if (csvPath) {
    const bool fresh = !std::filesystem::exists(csvPath);
    csv = std::fopen(csvPath, "a");
    if (!csv) {
      std::fprintf(stderr, "contact_cases: cannot write %s\n", csvPath);
      return 1;
    }
    if (fresh)
      std::fprintf(csv,
                   "scene,variant,frame,between,within,contacts_per_substep,energy_above,"
                   "new_pairs,new_where_none,deepest_new_where_none,new_apart_at_start,"
                   "deepest_new_apart_at_start,frozen_bodies,moved_as_one\n");
  }
  try {
    // A mesh file is the scene `softbake run FILE` makes of it.
    SceneFile file = std::filesystem::path(argv[1]).extension() == ".json"
                         ? loadSceneFile(argv[1])
                         : sceneFromMeshFile(argv[1]);
    SimulationSettings& settings = file.setup.settings;
    if (frames > 0) settings.frames = frames;
    if (argc > 2 && !parseIntegrator(argv[2], settings.integrator))
      throw Error(std::string("unknown integrator ") + argv[2]);
    if (argc > 3 && !parseInitialOverlapMode(argv[3], settings.collisions.initialOverlap))
      throw Error(std::string("unknown initial_overlap ") + argv[3]);
    if (argc > 4) settings.collisions.failsafe = std::strcmp(argv[4], "nofailsafe") != 0;
    if (argc > 5) settings.collisions.contactsInStep = std::strcmp(argv[5], "instep") == 0;
    const std::string variant =
        std::string(integratorName(settings.integrator)) +
        (settings.collisions.failsafe ? "" : ", no failsafe") +
        (settings.collisions.contactsInStep ? ", contacts in the step" : "");
    Simulator simulator(buildSceneTopology(file.setup));
    simulator.measureStages(true);
    simulator.measureStageEnergy(stageEnergy);
    const double start = computeEnergy(simulator.topology(), simulator.state()).total();
    const test::IntersectionCount atStart =
        test::countIntersectingPairs(simulator.collision(), simulator.state().position);
    const std::vector<std::pair<Index, Index>> overlapping =
        overlappingSurfaces(simulator.initialOverlaps());
    // Where the scene placed every particle, for how far apart a new pair's triangles stood.
    const std::vector<Vec3> startPosition(simulator.state().position.begin(),
                                          simulator.state().position.end());
    std::size_t worstNew = 0, worstNewWhereNone = 0, worstNewApart = 0;
    double deepestNewWhereNone = 0, deepestNewApart = 0;
    double highest = start, responseSeconds = 0;
    std::size_t worstBetween = 0, worstWithin = 0, framesBetween = 0, framesWithin = 0;
    std::size_t contacts = 0, substeps = 0;
    int reached = 1;
    std::string failure;
    const auto wallStart = std::chrono::steady_clock::now();
    double checkSeconds = 0;
    for (int frame = 2; frame <= settings.frames; ++frame) {
      try {
        simulator.beginFrame();
        for (int s = 0; s < simulator.substeps().substeps; ++s) {
          simulator.step(frame);
          const StageTimes& times = simulator.lastStepTimes();
          responseSeconds += 1e-9 * double(times.nanoseconds[int(Stage::Response)] +
                                           times.nanoseconds[int(Stage::Failsafe)]);
        }
      } catch (const Error& error) {
        failure = error.what();
        break;
      }
      reached = frame;
      substeps += std::size_t(simulator.substeps().substeps);
      contacts += simulator.lastFrameStats().contacts;
      const auto checkStart = std::chrono::steady_clock::now();
      const test::IntersectionCount count =
          test::countIntersectingPairs(simulator.collision(), simulator.state().position);
      checkSeconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - checkStart).count();
      std::size_t newPairs = 0, newWhereNone = 0, newApart = 0;
      double deepest = 0, deepestApart = 0;
      const CollisionGeometry& geometry = simulator.collision();
      const std::span<const Vec3> at = simulator.state().position;
      for (const auto& pair : count.pairs) {
        if (std::binary_search(atStart.pairs.begin(), atStart.pairs.end(), pair)) continue;
        ++newPairs;
        const Index a = geometry.triangleSurface[pair.first];
        const Index b = geometry.triangleSurface[pair.second];
        if (atStart.bySurfaces.count({std::min(a, b), std::max(a, b)})) continue;
        ++newWhereNone;
        const double depth = test::penetrationDepth(geometry.corners(at, pair.first),
                                                    geometry.corners(at, pair.second));
        deepest = std::max(deepest, depth);
        const bool touching =
            test::touchingWithinRounding(geometry.corners(startPosition, pair.first),
                                         geometry.corners(startPosition, pair.second));
        if (!touching) {
          ++newApart;
          deepestApart = std::max(deepestApart, depth);
        }
        if (deepMicrons >= 0 && 1e6 * depth > deepMicrons) {
          const TrianglePair ordered{std::min(pair.first, pair.second),
                                     std::max(pair.first, pair.second)};
          const bool fitted = std::binary_search(simulator.fittedPairs().begin(),
                                                 simulator.fittedPairs().end(), ordered);
          const std::array<int, 2> through = test::edgesThrough(geometry.corners(at, pair.first),
                                                                geometry.corners(at, pair.second));
          std::fprintf(stderr,
                       "deep frame %d: triangles %u and %u, surfaces %u and %u, %.1f µm, edges "
                       "through %d and %d, %.1f µm apart at the start%s%s%s\n",
                       frame, unsigned(pair.first), unsigned(pair.second), unsigned(a), unsigned(b),
                       1e6 * depth, through[0], through[1],
                       1e6 * test::triangleDistance(geometry.corners(startPosition, pair.first),
                                                    geometry.corners(startPosition, pair.second)),
                       fitted ? ", fitted" : "",
                       touching ? ", touching at the start within rounding" : "",
                       std::binary_search(overlapping.begin(), overlapping.end(),
                                          std::pair(std::min(a, b), std::max(a, b)))
                           ? ", surfaces overlapping at the start by the simulator's test"
                           : "");
        }
      }
      worstNew = std::max(worstNew, newPairs);
      worstNewWhereNone = std::max(worstNewWhereNone, newWhereNone);
      deepestNewWhereNone = std::max(deepestNewWhereNone, deepest);
      worstNewApart = std::max(worstNewApart, newApart);
      deepestNewApart = std::max(deepestNewApart, deepestApart);
      worstBetween = std::max(worstBetween, count.betweenSurfaces);
      worstWithin = std::max(worstWithin, count.withinSurfaces);
      framesBetween += count.betweenSurfaces > 0;
      framesWithin += count.withinSurfaces > 0;
      const double energy = computeEnergy(simulator.topology(), simulator.state()).total();
      highest = std::max(highest, energy);
      if (stageEnergy) {
        std::fprintf(stderr, "stage energy frame %d, J:", frame);
        const StageEnergies& stages = simulator.lastFrameStats().stageEnergy;
        for (int stage = 0; stage < kStageCount; ++stage)
          if (stages[stage] != 0)
            std::fprintf(stderr, " %s %+.3f", stageName(Stage(stage)), stages[stage]);
        std::fprintf(stderr, "\n");
      }
      if (csv)
        std::fprintf(
            csv, "%s,\"%s\",%d,%zu,%zu,%.1f,%.4f,%zu,%zu,%.3g,%zu,%.3g,%zu,%zu\n",
            std::filesystem::path(argv[1]).stem().string().c_str(), variant.c_str(), frame,
            count.betweenSurfaces, count.withinSurfaces,
            double(simulator.lastFrameStats().contacts) / double(simulator.substeps().substeps),
            energy - start, newPairs, newWhereNone, deepest, newApart, deepestApart,
            simulator.lastFrameStats().failsafe.frozenBodies,
            simulator.lastFrameStats().failsafe.bodiesMovedAsOne);
      // Each frame's row as it is made: a long bake cut short by a time limit keeps its frames.
      if (csv) std::fflush(csv);
    }
    if (csv) std::fclose(csv);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count() -
        checkSeconds;
    std::size_t triangles = 0;
    for (const Body& body : simulator.topology().bodies) triangles += body.triangleCount;
    std::printf(
        "| %s | %s | %zu | %zu | %s | %zu (%zu frames) | %zu (%zu frames) | %.0f | %.3f | %.2f | "
        "%.1f | %.2f | %zu | %zu | %.2f | %zu | %.2f |\n",
        std::filesystem::path(argv[1]).stem().string().c_str(), variant.c_str(),
        simulator.topology().bodies.size(), triangles,
        failure.empty() ? std::to_string(reached).c_str()
                        : ("blew up at " + std::to_string(reached + 1)).c_str(),
        worstBetween, framesBetween, worstWithin, framesWithin,
        substeps ? double(contacts) / double(substeps) : 0.0,
        substeps ? 1e3 * responseSeconds / double(substeps) : 0.0, highest - start,
        double(reached - 1) / wall, reached > 1 ? double(substeps) / double(reached - 1) : 0.0,
        worstNew, worstNewWhereNone, 1e6 * deepestNewWhereNone, worstNewApart,
        1e6 * deepestNewApart);
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "contact_cases: %s\n", error.what());
    return 1;
  }
}
