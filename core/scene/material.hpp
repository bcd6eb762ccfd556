#pragma once
/// Material parameters of a soft body and the named presets that span "from stiff to elastic".

#include <optional>
#include <span>
#include <string_view>

#include "core/types.hpp"

namespace softbake {

/// Every value is independent of mesh resolution and body size, so a preset behaves alike on a
/// 1k-face and a 100k-face mesh.
struct Material {
  /// Structural spring stiffness, N/m. For a regular triangulation this is the membrane's
  /// stretch stiffness, which does not change when the mesh is refined.
  Scalar stiffness = 1000;
  /// Bending spring stiffness, N/m (springs across each pair of edge-adjacent triangles).
  Scalar bendStiffness = 300;
  /// Fraction of critical damping of each spring along its axis, 0..1.
  Scalar damping = 0.05f;
  /// Gas pressure at the rest volume, Pa. The gas amount is fixed from it: nRT = pressure·V_rest,
  /// and P = nRT/V afterwards (Matyka & Ollila). Ignored on open meshes.
  Scalar pressure = 100;
  /// An open surface's two-sided skin, scene units: the collision failsafe keeps particles and
  /// edges on either side of a sheet at least this far from it (core/collision/failsafe.hpp). A
  /// sheet has no inside, so nothing else gives it a side to be on. Ignored on closed meshes. It
  /// should stay well under the mesh's edge length: the sheet's own vertices closer than it would
  /// push each other apart.
  Scalar thickness = Scalar(0.0005);
  /// Bulk modulus of what a closed body holds, Pa: the body resists a change of its volume V
  /// with the pressure K·(1 − V/V_rest) on top of its gas's, so it keeps its volume under load as
  /// jelly, rubber and flesh do (Jolt's and Vellum's volume constraints do the same). 0 leaves the
  /// paper's gas law alone (P = nRT/V), under which a loaded body loses a large part of its volume:
  /// the figure examples keep it. Ignored on open meshes.
  Scalar bulkModulus = 40000;
};

struct NamedMaterial {
  std::string_view name;
  std::string_view description;
  Material material;
};

/// The presets in the order of docs/materials.md: stiff, rubber, jelly, balloon (the last soft
/// in its springs, held up by its gas).
std::span<const NamedMaterial> materialPresets();

/// The preset called `name`, or nothing.
std::optional<Material> findMaterialPreset(std::string_view name);

}  // namespace softbake
