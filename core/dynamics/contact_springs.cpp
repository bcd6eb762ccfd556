#include "core/dynamics/contact_springs.hpp"

#include <algorithm>
#include <cmath>

#include "core/union_find.hpp"

namespace softbake {

void ContactSprings::set(std::span<const ContactStencil> stencils, const Scalar* inverseMass) {
  for (Index i : touched_) rowOf_[i] = kNoRow;
  stencils_.assign(stencils.begin(), stencils.end());
  const std::size_t count = stencils_.size();
  stiffness_.resize(count);
  freeWeight_.resize(count);
  gap0_.assign(count, 0);
  bias_.assign(count, 0);
  active_.assign(count, 0);
  tangentCoefficient_.assign(count, 0);
  direction_.resize(3 * count);
  approach_.assign(3 * count, 0);
  coefficient_.assign(3 * count, 0);
  rhsScale_.assign(3 * count, 0);
  activeCount_ = 0;
  sortScratch_.clear();
  for (std::size_t s = 0; s < count; ++s) {
    ContactStencil& stencil = stencils_[s];
    double resistance = 0;  // Σ w²/m over the moving corners
    freeWeight_[s] = 0;
    for (Index k = 0; k < 4; ++k) {
      const Index p = stencil.particle[k];
      if (p == ContactStencil::kFixed || inverseMass[p] == 0) continue;
      freeWeight_[s] += stencil.weight[k];
      resistance += double(stencil.weight[k]) * stencil.weight[k] * inverseMass[p];
      sortScratch_.push_back({p, {Index(s), k}});
    }
    stiffness_[s] = resistance > 0 ? Scalar(double(kStiffness) / resistance) : Scalar(0);
    // Two tangents, for friction.
    const Vec3& n = stencil.normal;
    const Vec3 tangent =
        (std::abs(n.x()) < Scalar(0.9) ? n.cross(Vec3::UnitX()) : n.cross(Vec3::UnitY()))
            .normalized();
    direction_[3 * s] = n;
    direction_[3 * s + 1] = tangent;
    direction_[3 * s + 2] = n.cross(tangent);
  }
  // Keys are unique (a stencil names a particle once), so the order is total: the same for any
  // thread count.
  std::sort(sortScratch_.begin(), sortScratch_.end());
  touched_.clear();
  incidence_.clear();
  incidenceStart_.clear();
  for (const auto& [particle, entry] : sortScratch_) {
    if (touched_.empty() || touched_.back() != particle) {
      rowOf_[particle] = Index(touched_.size());
      touched_.push_back(particle);
      incidenceStart_.push_back(Index(incidence_.size()));
    }
    incidence_.push_back(entry);
  }
  incidenceStart_.push_back(Index(incidence_.size()));
  baseDiagonal_.resize(touched_.size());
  baseRhs_.resize(touched_.size());
}

Vec3 ContactSprings::weightedSum(const ContactStencil& stencil, const Vec3* x) const {
  Vec3 sum = Vec3::Zero();
  for (Index k = 0; k < 4; ++k)
    if (stencil.particle[k] != ContactStencil::kFixed)
      sum += stencil.weight[k] * x[stencil.particle[k]];
  return sum;
}

void ContactSprings::refresh(std::size_t s, Scalar h) {
  Scalar* coefficient = &coefficient_[3 * s];
  Scalar* rhsScale = &rhsScale_[3 * s];
  std::fill(coefficient, coefficient + 3, Scalar(0));
  std::fill(rhsScale, rhsScale + 3, Scalar(0));
  if (!active_[s]) return;
  const Scalar c = stiffness_[s];
  coefficient[0] = c;
  rhsScale[0] = c * ((gap0_[s] - bias_[s]) / h + approach_[3 * s]);
  if (!(stencils_[s].friction > 0)) return;
  for (int d = 1; d < 3; ++d) {
    coefficient[d] = tangentCoefficient_[s];
    rhsScale[d] = tangentCoefficient_[s] * approach_[3 * s + d];
  }
}

void ContactSprings::begin(const Vec3* x0, const Vec3* v0, const Vec3& gravity, Scalar h) {
  activeCount_ = 0;
  for (std::size_t s = 0; s < stencils_.size(); ++s) {
    const ContactStencil& stencil = stencils_[s];
    const Scalar gap = stencil.normal.dot(weightedSum(stencil, x0)) + stencil.offset;
    const Vec3 velocity = weightedSum(stencil, v0);
    for (int d = 0; d < 3; ++d) approach_[3 * s + d] = direction_[3 * s + d].dot(velocity);
    const Scalar fall = freeWeight_[s] * stencil.normal.dot(gravity);
    gap0_[s] = gap;
    bias_[s] = 0;
    tangentCoefficient_[s] = stencil.friction > 0 ? stiffness_[s] : Scalar(0);
    active_[s] = gap + h * (approach_[3 * s] + h * fall) < 0;
    activeCount_ += std::size_t(active_[s]);
    refresh(s, h);
  }
}

std::pair<std::size_t, std::size_t> ContactSprings::rowsIn(std::size_t begin,
                                                           std::size_t end) const {
  const auto first = std::lower_bound(touched_.begin(), touched_.end(), Index(begin));
  const auto last = std::lower_bound(first, touched_.end(), Index(end));
  return {std::size_t(first - touched_.begin()), std::size_t(last - touched_.begin())};
}

void ContactSprings::applyRows(Vec3* rhs, Mat3* inverseDiagonal, std::size_t begin,
                               std::size_t end) const {
  const auto [first, last] = rowsIn(begin, end);
  for (std::size_t row = first; row < last; ++row) {
    const Index i = touched_[row];
    Mat3 diagonal = baseDiagonal_[row];
    Vec3 b = baseRhs_[row];
    for (Index e = incidenceStart_[row]; e < incidenceStart_[row + 1]; ++e) {
      const auto [s, corner] = incidence_[e];
      if (!active_[s]) continue;
      const Scalar w = stencils_[s].weight[corner];
      for (int d = 0; d < 3; ++d) {
        const Vec3& direction = direction_[3 * s + d];
        diagonal += (coefficient_[3 * s + d] * w * w) * direction * direction.transpose();
        b -= (rhsScale_[3 * s + d] * w) * direction;
      }
    }
    rhs[i] = b;
    inverseDiagonal[i] = diagonal.inverse();
  }
}

double ContactSprings::multiply(const Vec3* x, Vec3* out, std::size_t begin,
                                std::size_t end) const {
  // Each particle computes the g·x of its own stencils, so a stencil's is computed once per
  // corner, up to four times: a few hundred stencils against thousands of particles, where a
  // pass of its own over the stencils first cost every CG iteration a barrier more.
  double curvature = 0;
  const auto [first, last] = rowsIn(begin, end);
  for (std::size_t row = first; row < last; ++row) {
    const Index i = touched_[row];
    Vec3 sum = Vec3::Zero();
    for (Index e = incidenceStart_[row]; e < incidenceStart_[row + 1]; ++e) {
      const auto [s, corner] = incidence_[e];
      if (!active_[s]) continue;
      const Vec3 along = weightedSum(stencils_[s], x);
      const Scalar w = stencils_[s].weight[corner];
      for (std::size_t d = 3 * s; d < 3 * s + 3; ++d)
        sum += (coefficient_[d] * direction_[d].dot(along) * w) * direction_[d];
    }
    out[i] += sum;
    curvature += double(x[i].dot(sum));
  }
  return curvature;
}

std::size_t ContactSprings::update(const Vec3* v0, const Vec3* deltaV, Scalar h, Scalar tolerance) {
  std::size_t changed = 0;
  for (std::size_t s = 0; s < stencils_.size(); ++s) {
    const ContactStencil& stencil = stencils_[s];
    const Vec3 velocity = weightedSum(stencil, v0) + weightedSum(stencil, deltaV);
    const Scalar gap = gap0_[s] + h * stencil.normal.dot(velocity);
    const bool wasActive = active_[s];
    if (active_[s] && gap < -tolerance && !stencil.fitted) {
      // Augmented Lagrangian: the spring keeps the force it needed and adds what it is short of.
      // Not between fitted parts: a fit's hold stops its vertex but never pushes it, and springs
      // raised beside holds that cannot give way pushed the fitted parts of a house out of their
      // fits, 64 MJ in two seconds (bench/results/assemblies.md).
      bias_[s] -= gap;
      ++changed;
    } else {
      const bool active = active_[s] ? gap <= bias_[s] : gap < 0;
      if (active != bool(active_[s])) {
        ++changed;
        activeCount_ += std::size_t(active) - std::size_t(bool(active_[s]));
        active_[s] = active;
        if (!active) {
          bias_[s] = 0;
          tangentCoefficient_[s] = stencil.friction > 0 ? stiffness_[s] : Scalar(0);
        }
      }
    }
    if (wasActive && active_[s] && stencil.friction > 0) {
      // Coulomb: the tangential damping sticks (c) while its impulse c·|u_t| stays within μ times
      // the normal impulse, and slides with μ·J_n/|u_t| beyond: a damping, so friction never
      // turns the motion round or adds energy, and its impulse never exceeds the bound.
      const Scalar normalImpulse = std::max(Scalar(0), stiffness_[s] * (bias_[s] - gap) / h);
      const Vec3 tangential = velocity - stencil.normal.dot(velocity) * stencil.normal;
      const Scalar speed = tangential.norm();
      const Scalar bound = stencil.friction * normalImpulse;
      const Scalar damping = stiffness_[s] * speed > bound ? bound / speed : stiffness_[s];
      if (std::abs(damping - tangentCoefficient_[s]) > kFrictionSlack * tangentCoefficient_[s])
        ++changed;
      tangentCoefficient_[s] = damping;
    }
    refresh(s, h);
  }
  return changed;
}

void ContactSprings::joinBodies(const Index* particleBody, std::vector<Index>& group,
                                std::vector<char>& held) const {
  for (std::size_t s = 0; s < stencils_.size(); ++s) {
    if (!active_[s]) continue;
    Index first = ContactStencil::kFixed;
    bool fixed = false;
    for (Index k = 0; k < 4; ++k) {
      const Index p = stencils_[s].particle[k];
      if (p == ContactStencil::kFixed) {
        fixed = true;
        continue;
      }
      const Index root = findRoot(group, particleBody[p]);
      if (first == ContactStencil::kFixed) {
        first = root;
      } else if (root != first) {
        first = joinRoots(group, root, first);
      }
    }
    if (fixed && first != ContactStencil::kFixed) held[first] = 1;
  }
  for (Index b = 0; b < group.size(); ++b) group[b] = findRoot(group, b);
}

}  // namespace softbake
