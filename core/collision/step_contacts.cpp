#include "core/collision/step_contacts.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/collision/continuous_collision.hpp"
#include "core/collision/detection.hpp"
#include "core/collision/failsafe.hpp"

namespace softbake {

namespace {
/// Chunks of candidate pairs: enough for TBB to balance uneven chunks.
constexpr std::size_t kPairChunks = 128;
/// An empty slot of the set of a triangle's partners' corners.
constexpr Index kNoCorner = ~Index(0);
/// Marks a partner, or a corner, that only a fitted pair brings: the top bit, free while a scene
/// has fewer than 2³¹ collision vertices and triangles (a mesh that size would not fit in memory).
constexpr Index kHoldOnly = Index(1) << 31;
}  // namespace

StepContacts::StepContacts(const SceneTopology& topology, const CollisionGeometry& geometry)
    : broadPhase_(makeBroadPhase(BroadPhaseKind::Bvh)) {
  const Scalar skin = topology.settings.skin;
  gap_.assign(geometry.surfaces.size(), skin);
  fittedSurface_.assign(geometry.surfaces.size(), 0);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b)
    gap_[b] = std::max(skin, Scalar(openSurfaceThickness(topology, topology.bodies[b])));
  predicted_.resize(topology.particleCount());
  reach_.assign(geometry.particleCount + geometry.staticVertex.size(), 0);
  vertexBoxes_.resize(reach_.size());
  for (std::size_t v = geometry.particleCount; v < vertexBoxes_.size(); ++v) {
    const Vec3& x = geometry.staticVertex[v - geometry.particleCount];
    vertexBoxes_[v] = Box3(Vec3(x.array() - skin), Vec3(x.array() + skin));
  }
  boxes_.resize(geometry.triangleVertices.size());
  vertexSurface_.assign(reach_.size(), 0);
  for (std::size_t t = 0; t < geometry.triangleVertices.size(); ++t)
    for (Index v : geometry.triangleVertices[t]) vertexSurface_[v] = geometry.triangleSurface[t];
}

namespace {

// How far the foot of `x` on the plane of (a, b, c) lies outside the triangle, past the edge it
// is furthest past (a lower bound of its distance from the triangle); 0 on the triangle.
Scalar footOutside(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x) {
  const Vec3 normal = (b - a).cross(c - a);
  const Scalar area2 = normal.norm();
  if (!(area2 > 0)) return 0;
  // The foot's signed distance inside edge (p, q) is ((q - p) × (x - p)) · n / |q - p|, n the
  // unit normal.
  Scalar outside = 0;
  const auto pastEdge = [&](const Vec3& p, const Vec3& q) {
    const Vec3 edge = q - p;
    const Scalar inside = edge.cross(x - p).dot(normal);
    if (inside < 0) outside = std::max(outside, -inside / (area2 * edge.norm()));
  };
  pastEdge(a, b);
  pastEdge(b, c);
  pastEdge(c, a);
  return outside;
}

}  // namespace

void StepContacts::tryVertex(const SceneTopology& topology, const CollisionGeometry& geometry,
                             std::span<const Vec3> start,
                             std::span<const std::pair<Index, Index>> overlapping, Index v,
                             Index triangle, std::vector<Found>& out) const {
  const bool holdOnly = (v & kHoldOnly) != 0;
  v &= ~kHoldOnly;
  const Triangle& corners = geometry.triangleVertices[triangle];
  if (hasVertex(corners, v)) return;
  const Index particles = geometry.particleCount;
  const bool vertexFixed = v >= particles || topology.inverseMass[v] == 0;
  bool triangleFixed = true;
  for (Index c : corners)
    triangleFixed = triangleFixed && (c >= particles || topology.inverseMass[c] == 0);
  if (vertexFixed && triangleFixed) return;
  const Vec3& a = geometry.vertex(start, corners[0]);
  const Vec3& b = geometry.vertex(start, corners[1]);
  const Vec3& c = geometry.vertex(start, corners[2]);
  const Vec3& x = geometry.vertex(start, v);
  const Vec3 ab = b - a, ac = c - a, ax = x - a;
  Vec3 normal = ab.cross(ac);
  const Scalar area2 = normal.norm();
  if (!(area2 > 0)) return;
  normal /= area2;
  Scalar distance = normal.dot(ax);
  const Index surface = geometry.triangleSurface[triangle];
  const Index vertexSurface = vertexSurface_[v];
  const Scalar gap = std::max(gap_[surface], gap_[vertexSurface]);
  const auto rest = [&](Index u) -> const Vec3& {
    return geometry.vertex(topology.restPosition, u);
  };
  const auto restDouble = [&](Index u) -> Vec3d { return rest(u).cast<double>(); };
  const auto placedWithinGap = [&] {
    return pointTriangleDistance(restDouble(v), restDouble(corners[0]), restDouble(corners[1]),
                                 restDouble(corners[2])) < gap;
  };
  // How far in front of the triangle's plane the scene placed the vertex, along the normal.
  const auto placedInFront = [&] {
    const Vec3 restNormal = (rest(corners[1]) - rest(corners[0]))
                                .cross(rest(corners[2]) - rest(corners[0]))
                                .normalized();
    return restNormal.dot(rest(v) - rest(corners[0]));
  };
  // A vertex that only fitted pairs bring (parts of an assembly fitted onto each other), placed in
  // front of another surface's triangle within the gap, is held no nearer that face than it was
  // placed, or than it is where it has come nearer: its spring stops it going deeper and never
  // pushes it out, so the fit stores no energy, and once behind the face it is held where it is.
  // Left to the failsafe alone, which counts a fitted crossing only beyond its separation and
  // leaves one already crossed alone, such vertices of an engine sank through their mates 171 µm
  // deep by frame 13 (bench/results/assemblies.md). Left to it while still in front, a block
  // fitted on another sank into its base in every substep, by the substep's fall, and was lifted
  // back by the failsafe and the edge pushes, 600 to 1 000 meetings a frame: it crept 27 mm in
  // two seconds (bench/results/contacts.md). Behind a closed surface is
  // inside it (tangled, or left to the response and the failsafe), but a vertex its own closed
  // surface placed in front of the triangle within the gap (a part's walls or fillets modelled
  // closer than the skin) is held so too: the failsafe gives such meetings as it gives fits, and
  // one of an engine's parts went 110 µm through itself by frame 14.
  const bool behind = distance < 0;
  const bool closedBehind = behind && geometry.surfaceClosed[surface];
  const bool hold = holdOnly ? vertexSurface != surface : closedBehind && vertexSurface == surface;
  if (hold) {
    // Placed behind the face, it started inside: an overlap set aside, which may slide out of
    // itself. (A hold of its own closed surface is behind.) Between surfaces that overlapped at
    // the start, one still in front gives: held there, the rim of two balls placed into each
    // other held against the set-aside overlap beside it, and pushed the balls apart.
    if (!placedWithinGap() || placedInFront() < 0) return;
    if (!behind && holdsSurfacePair(overlapping, surface, vertexSurface)) return;
  } else if (holdOnly || closedBehind) {
    return;
  } else if (behind) {
    normal = -normal;
    distance = -distance;
  }
  Scalar reach = reach_[v];
  for (Index corner : corners) reach = std::max(reach, reach_[corner]);
  const auto predicted = [&](Index u) -> const Vec3& {
    return u < particles ? predicted_[u] : geometry.staticVertex[u - particles];
  };
  // Most candidates end here, before the foot: far from the plane through corner 0 at the start
  // and as predicted. (The foot's plane point differs from corner 0's predicted one by at most
  // the corners' departures from their body's mean travel, 4·reach.)
  const Scalar planeDistance = normal.dot(predicted(v) - predicted(corners[0]));
  if (std::min(distance, planeDistance) > 2 * gap + 8 * reach) return;
  const std::optional<std::array<Scalar, 3>> foot = footBarycentric(a, b, c, x);
  if (!foot) return;
  const auto [alpha, beta, gamma] = *foot;
  if (alpha < -kFootTolerance || beta < -kFootTolerance || gamma < -kFootTolerance) return;
  // The tolerance above is relative, so on a large triangle it reaches far past its edges: the
  // walls of a house butting edge to edge in one plane each had their corners in the next wall's
  // triangles, were held a gap out of that plane, and pushed each other for 20 s a step. A vertex
  // whose foot lies outside the triangle by `outside` is at least that far from it: beyond the
  // gap and its reach, at the start and as predicted, it needs no stencil.
  const Scalar beyond = gap + 4 * reach;
  const Scalar outside = footOutside(a, b, c, x);
  if (outside > beyond && footOutside(predicted(corners[0]), predicted(corners[1]),
                                      predicted(corners[2]), predicted(v)) > beyond)
    return;
  // Where the predicted motion takes the vertex relative to the triangle's plane (held fixed),
  // give or take its reach: beyond that, it cannot come within the gap over the step.
  const Scalar predictedDistance =
      normal.dot(predicted(v) - alpha * predicted(corners[0]) - beta * predicted(corners[1]) -
                 gamma * predicted(corners[2]));
  if (std::min(distance, predictedDistance) > 2 * gap + 4 * reach) return;
  // No stencil pushes a vertex the scene placed where it is. Off the triangle, the plane need only
  // keep a vertex sqrt(gap² - lateral²) away for it to keep the gap from the triangle, lateral
  // its foot's distance from the triangle: held to the whole gap, a house's parts were pushed
  // apart from the first step in free fall (750 stencils held) and their fittings into
  // themselves.
  Scalar keep = gap;
  if (outside > 0) {
    const double away = pointTriangleDistance(x.cast<double>(), a.cast<double>(), b.cast<double>(),
                                              c.cast<double>());
    const double lateral2 = std::max(0.0, away * away - double(distance) * distance);
    keep = Scalar(std::sqrt(std::max(0.0, double(gap) * gap - lateral2)));
  }
  // A vertex its own surface placed within the gap of the triangle (the walls and fillets of a
  // CAD part, a folded sheet) is kept no nearer its plane than it was placed there, measured along
  // the normal as the stencil measures: held to the whole gap, each part pushed its own walls
  // apart and into the next part, and an engine of 115 parts took four times as long a step. (A
  // flat flag's vertices lie in the plane of all its triangles, but within the gap of few: its
  // folds are held to the gap.) A hold (above) keeps the vertex no nearer than it was placed or
  // is now, whichever is nearer: behind the face, where it is.
  if (hold) {
    keep = std::min(distance, placedInFront());
  } else if (vertexSurface == surface && placedWithinGap()) {
    const Scalar placed = placedInFront();
    keep = std::min(keep, std::max(Scalar(0), behind ? -placed : placed));
  }
  ContactStencil stencil;
  stencil.normal = normal;
  const std::array<Index, 4> vertices{v, corners[0], corners[1], corners[2]};
  const std::array<Scalar, 4> weights{1, -alpha, -beta, -gamma};
  Scalar offset = -keep;
  for (int k = 0; k < 4; ++k) {
    if (vertices[k] >= particles) {
      offset += weights[k] * normal.dot(geometry.vertex(start, vertices[k]));
      continue;
    }
    stencil.particle[k] = vertices[k];
    stencil.weight[k] = weights[k];
  }
  stencil.offset = offset;
  stencil.friction =
      Scalar(std::sqrt(double(geometry.friction[surface]) * geometry.friction[vertexSurface]));
  stencil.fitted = hold || fittedSurface_[surface] || fittedSurface_[vertexSurface];
  out.push_back({(std::uint64_t(v) << 32) | triangle, stencil});
}

std::span<const ContactStencil> StepContacts::find(
    const SceneTopology& topology, const CollisionGeometry& geometry, CollisionDetector& detector,
    const SimulationState& state, Scalar dt, std::span<const std::pair<Index, Index>> overlapping) {
  const Vec3 fall = dt * dt * topology.settings.gravity;
  const std::span<const Vec3> start = state.position;
  // The reach: half of how far each particle's predicted travel departs from its body's mean
  // travel, what the solve may change. A body moving as one (falling, flying) reaches no further
  // than its swept boxes: grown by the whole travel, the boxes of 300 beads falling together in
  // one body overlapped by the hundred million pairs. One pass per body, the prediction included:
  // each parallel loop is a barrier of the step.
  tbb::parallel_for(std::size_t(0), topology.bodies.size(), [&](std::size_t b) {
    const Body& body = topology.bodies[b];
    const Index end = body.firstParticle + body.particleCount;
    Vec3d sum = Vec3d::Zero();
    for (Index i = body.firstParticle; i < end; ++i) {
      const Vec3& x = start[i];
      predicted_[i] = topology.inverseMass[i] == 0 ? x : Vec3(x + dt * state.velocity[i] + fall);
      sum += (predicted_[i] - x).cast<double>();
    }
    const Vec3 mean =
        body.particleCount ? Vec3((sum / double(body.particleCount)).cast<Scalar>()) : Vec3::Zero();
    for (Index i = body.firstParticle; i < end; ++i) {
      reach_[i] = Scalar(0.5) * (predicted_[i] - start[i] - mean).norm();
      const Scalar grow = topology.settings.skin + reach_[i];
      Box3 box(start[i].cwiseMin(predicted_[i]), start[i].cwiseMax(predicted_[i]));
      vertexBoxes_[i] = Box3(Vec3(box.min().array() - grow), Vec3(box.max().array() + grow));
    }
  });
  // Every gap is at least the skin: an open body's thicker gap grows its own boxes.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, boxes_.size(), kTriangleGrain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const Triangle& corners = geometry.triangleVertices[t];
                        Box3 box = vertexBoxes_[corners[0]];
                        box.extend(vertexBoxes_[corners[1]]).extend(vertexBoxes_[corners[2]]);
                        const Scalar extra =
                            gap_[geometry.triangleSurface[t]] - topology.settings.skin;
                        if (extra > 0) {
                          box.min().array() -= extra;
                          box.max().array() += extra;
                        }
                        boxes_[t] = box;
                      }
                    });
  const BroadPhaseInput input = geometry.broadPhaseInput(boxes_, &detector.flatPatches());
  if (!detector.findCachedPairs(input, pairs_)) pairCache_.findPairs(*broadPhase_, input, pairs_);
  // The fitted pairs stay: their vertices are held as the scene placed them (tryVertex).
  detector.dropIgnoredPairs(geometry, pairs_);

  // A vertex meets a triangle through each of its own triangles paired with it, 2.7 times on
  // average on figure 7. So each triangle gathers the corners of the triangles paired with it
  // (from the pairs laid out per triangle, a counting sort), drops repeats, and measures each
  // corner once.
  const std::size_t triangles = boxes_.size();
  partnerStart_.assign(triangles + 1, 0);
  for (const TrianglePair& pair : pairs_)
    ++partnerStart_[pair.first + 1], ++partnerStart_[pair.second + 1];
  for (std::size_t t = 0; t < triangles; ++t) partnerStart_[t + 1] += partnerStart_[t];
  partner_.resize(2 * pairs_.size());
  partnerFill_.assign(partnerStart_.begin(), partnerStart_.end() - 1);
  {
    const std::vector<TrianglePair>& fitted = detector.fittedPairs();
    std::fill(fittedSurface_.begin(), fittedSurface_.end(), 0);
    for (const TrianglePair& pair : fitted)
      fittedSurface_[geometry.triangleSurface[pair.first]] =
          fittedSurface_[geometry.triangleSurface[pair.second]] = 1;
    auto f = fitted.begin();
    for (const TrianglePair& pair : pairs_) {
      while (f != fitted.end() && *f < pair) ++f;
      const Index flag = (f != fitted.end() && *f == pair) ? kHoldOnly : 0;
      partner_[partnerFill_[pair.first]++] = pair.second | flag;
      partner_[partnerFill_[pair.second]++] = pair.first | flag;
    }
  }
  const std::size_t chunks = pairs_.empty() ? 0 : kPairChunks;
  chunkFound_.reset(chunks);
  chunkCorners_.reset(chunks);
  chunkSeen_.reset(chunks);
  if (chunks > 0) {
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
      std::vector<Found>& out = chunkFound_[chunk];
      std::vector<Index>& corners = chunkCorners_[chunk];
      std::vector<Index>& seen = chunkSeen_[chunk];
      for (std::size_t t = triangles * chunk / chunks; t < triangles * (chunk + 1) / chunks; ++t) {
        if (partnerStart_[t] == partnerStart_[t + 1]) continue;
        // The corners, each once, through an open-addressed set at most half full: sorting them
        // to drop the repeats took a fifth of this stage.
        int bits = 4;
        while ((std::size_t(1) << bits) < 6 * std::size_t(partnerStart_[t + 1] - partnerStart_[t]))
          ++bits;
        const std::size_t mask = (std::size_t(1) << bits) - 1;
        seen.assign(mask + 1, kNoCorner);
        corners.clear();
        // A slot holds the corner's place in `corners`; a corner that an ordinary pair brings too
        // is measured as an ordinary one.
        const auto cornerAt = [&](std::size_t slot) { return corners[seen[slot]] & ~kHoldOnly; };
        for (Index k = partnerStart_[t]; k < partnerStart_[t + 1]; ++k) {
          const Index flag = partner_[k] & kHoldOnly;
          for (Index v : geometry.triangleVertices[partner_[k] & ~kHoldOnly]) {
            std::size_t slot = (std::uint32_t(v) * 2654435769u) >> (32 - bits);
            while (seen[slot] != kNoCorner && cornerAt(slot) != v) slot = (slot + 1) & mask;
            if (seen[slot] != kNoCorner) {
              corners[seen[slot]] &= flag | ~kHoldOnly;
              continue;
            }
            seen[slot] = Index(corners.size());
            corners.push_back(v | flag);
          }
        }
        for (Index v : corners) tryVertex(topology, geometry, start, overlapping, v, Index(t), out);
      }
    });
  }
  chunkFound_.reserveLargest();
  chunkFound_.join(found_);
  std::sort(found_.begin(), found_.end(),
            [](const Found& a, const Found& b) { return a.key < b.key; });
  stencils_.clear();
  for (const Found& found : found_) stencils_.push_back(found.stencil);
  return stencils_;
}

void StepContacts::appendHeld(const CollisionGeometry& geometry, std::span<const char> held,
                              std::span<const Vec3> positions,
                              std::vector<Contact>& contacts) const {
  for (std::size_t s = 0; s < held.size() && s < found_.size(); ++s) {
    if (!held[s]) continue;
    const Index v = Index(found_[s].key >> 32), triangle = Index(found_[s].key & 0xffffffffu);
    Contact contact;
    contact.kind = ContactKind::Held;
    contact.position = geometry.vertex(positions, v);
    contact.normal = found_[s].stencil.normal;
    contact.surfaceB = geometry.triangleSurface[triangle];
    contact.triangleB = triangle;
    if (v < geometry.particleCount) {
      contact.particle = v;
    }
    contact.surfaceA = vertexSurface_[v];
    contacts.push_back(contact);
  }
}

}  // namespace softbake
