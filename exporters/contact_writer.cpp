#include "exporters/contact_writer.hpp"

#include <nlohmann/json.hpp>

#include "core/text.hpp"
#include "output/atomic_file.hpp"
#include "output/finite_values.hpp"

namespace softbake {

namespace {
nlohmann::ordered_json vector(const Vec3& v) {
  return nlohmann::ordered_json::array({v.x(), v.y(), v.z()});
}
}  // namespace

ContactWriter::ContactWriter(const SceneTopology& topology,
                             const std::filesystem::path& outputDirectory, std::string scene,
                             int framePadding)
    : outputDirectory_(outputDirectory),
      naming_{"contacts", std::move(scene), ".json", framePadding} {
  for (const Body& body : topology.bodies) {
    surfaceNames_.push_back(body.name);
    bodyFirstParticle_.push_back(body.firstParticle);
  }
  for (const StaticMeshCollider& collider : topology.staticMeshes)
    surfaceNames_.push_back(collider.name);
  for (const PlaneCollider& plane : topology.planes) planeNames_.push_back(plane.name);
  for (Index surface = 0; surface < topology.surfaceCount(); ++surface)
    surfaceFirstTriangle_.push_back(topology.surfaceFirstTriangle(surface));
  makeDirectories(outputDirectory_ / naming_.folder);
}

const std::string& ContactWriter::partnerName(const Contact& contact) const {
  return contact.kind == ContactKind::Plane ? planeNames_[contact.surfaceB]
                                            : surfaceNames_[contact.surfaceB];
}

std::filesystem::path ContactWriter::framePath(int frameNumber) const {
  return outputDirectory_ / naming_.relativePath(frameNumber);
}

OutputSequence ContactWriter::sequence() const {
  return {"contacts", naming_.pattern(), naming_.printfPattern(), {}};
}

std::string ContactWriter::frameJson(const Frame& frame) const {
  nlohmann::ordered_json contacts = nlohmann::ordered_json::array();
  auto local = [&](Index triangle, Index surface) -> nlohmann::ordered_json {
    if (triangle == kNoIndex) return nullptr;
    return triangle - surfaceFirstTriangle_[surface];
  };
  for (const Contact& c : frame.contacts) {
    contacts.push_back({
        {"kind", contactKindName(c.kind)},
        {"position", vector(c.position)},
        {"normal", vector(c.normal)},
        {"bodies", nlohmann::ordered_json::array({surfaceNames_[c.surfaceA], partnerName(c)})},
        {"triangles", nlohmann::ordered_json::array(
                          {local(c.triangleA, c.surfaceA), local(c.triangleB, c.surfaceB)})},
        {"particle", c.particle == kNoIndex
                         ? nlohmann::ordered_json(nullptr)
                         : nlohmann::ordered_json(c.particle - bodyFirstParticle_[c.surfaceA])},
    });
  }
  nlohmann::ordered_json document;
  document["frame"] = frame.number;
  document["time"] = frame.time;
  document["scene"] = naming_.scene;
  document["contacts"] = std::move(contacts);
  return document.dump() + "\n";
}

void ContactWriter::write(const Frame& frame) {
  const std::filesystem::path path = framePath(frame.number);
  // JSON has no NaN: nlohmann would write null, which reads as a missing value, not an error.
  requireFinite(path, frame.time, [&] { return cat("frame ", frame.number, ": the time"); });
  requireFiniteContacts(path, frame, [&](std::size_t i) {
    const Contact& c = frame.contacts[i];
    return cat("contact ", i, " (", surfaceNames_[c.surfaceA], " on ", partnerName(c), ")");
  });
  const std::string text = frameJson(frame);
  writeFileAtomically(path, text);
  bytes_.fetch_add(text.size(), std::memory_order_relaxed);
}

}  // namespace softbake
