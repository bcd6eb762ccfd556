#pragma once
/// The matrix of the implicit step, M + Σ S over the springs, laid out for SIMD: the product that
/// conjugate gradients spends most of its time in.
///
/// Every spring couples its two ends by a symmetric 3×3 block S = α·d̂d̂ᵀ + β·I, kept as five
/// numbers (the axis d̂, α and β). Row i of the product is
///
///   (A·x)_i = m_i·x_i + Σ_{springs s at i} S_s·(x_i − x_other(s)).
///
/// The layout is sliced ELLPACK (Kreutzer et al., "A unified sparse matrix data format for
/// efficient general sparse matrix-vector multiplication on modern processors with wide SIMD
/// units", SIAM J. Sci. Comput. 2014; SELL-C-σ with C = kLanes and σ = 1): particles go in slices
/// of kLanes, each slice's rows are padded to its longest, and the neighbour and each of the five
/// numbers are stored slot by slot, a lane per particle. One pass over a slice computes its
/// particles' rows side by side, each lane in the order of its own incidence row, so every
/// particle's sum is the same operations in the same order as its row walked alone: the lanes
/// change no bit of the result, on any width of vector unit. A pinned neighbour and a padding slot
/// read an entry past the particles that the caller keeps at zero (a pinned Δv is zero: the
/// constraint filter), and a padding slot's block is zero as well.
///
/// The same layout assembles the blocks each step (assemble()): a slot computes its spring from its
/// own end, so the lanes write their slots in order, and each particle's force, diagonal block and
/// velocity terms are summed in its lanes, in row order, with nothing scattered. The two ends of a
/// spring compute it twice, from opposite sides; the results are exact negatives of each other
/// (d, v_b − v_a and d̂ change sign, |d| and d̂·d do not), and the product and the diagonal use d̂
/// twice, so either side's block is the same to the bit.
///
/// Where the processor has AVX2, the product and the assembly run in 256-bit registers (chosen
/// once at run time); elsewhere in SSE2's, with the same result. No FMA is used: a fused
/// multiply-add rounds once instead of twice and would change the result from one processor to
/// the next.

#include <cstddef>
#include <vector>

#include "core/scene/scene_topology.hpp"

namespace softbake {

class SlicedSpringMatrix {
 public:
  /// Particles per slice: eight floats fill an AVX register, two SSE ones.
  static constexpr std::size_t kLanes = 8;

  /// The layout of `topology`'s incidence rows. Pinned particles have empty rows; a pinned
  /// neighbour reads the zero entry.
  explicit SlicedSpringMatrix(const SceneTopology& topology);

  /// Length the product's vectors must have: whole slices plus the zero entry, which is entry
  /// particleCount() (the entries from particleCount() on are read as zero and must stay so).
  std::size_t paddedSize() const { return laneMass_.size() + 1; }

  /// No slot: the end of a spring at a pinned particle, whose row is empty.
  static constexpr std::size_t kNoSlot = std::size_t(-1);

  std::size_t slotCount() const { return neighbour_.size(); }
  /// The slot of the k-th spring of particle i's incidence row (topology.springRowStart).
  std::size_t slot(Index i, Index k) const {
    return (std::size_t(sliceStart_[i / kLanes]) + k) * kLanes + i % kLanes;
  }
  /// The slots of spring s in the rows of its ends a and b (kNoSlot at a pinned end).
  std::size_t slotAtA(std::size_t s) const { return springSlot_[2 * s]; }
  std::size_t slotAtB(std::size_t s) const { return springSlot_[2 * s + 1]; }

  /// Sets spring s's block α·d̂d̂ᵀ + β·I in the rows of both its ends.
  void setSpringBlock(std::size_t s, const Vec3& axis, Scalar along, Scalar isotropic) {
    for (const std::size_t at : {slotAtA(s), slotAtB(s)}) {
      if (at == kNoSlot) continue;
      axisX_[at] = axis.x();
      axisY_[at] = axis.y();
      axisZ_[at] = axis.z();
      along_[at] = along;
      isotropic_[at] = isotropic;
    }
  }
  Vec3 axis(std::size_t slot) const { return Vec3(axisX_[slot], axisY_[slot], axisZ_[slot]); }
  Scalar along(std::size_t slot) const { return along_[slot]; }
  Scalar isotropic(std::size_t slot) const { return isotropic_[slot]; }

  /// Whether multiply() runs in AVX2's registers: true where the processor has AVX2. Turned off, it
  /// runs in SSE2's, with the same result (a test compares the two).
  bool usesAvx2() const { return avx2_; }
  void useAvx2(bool on);

  /// The state a step's assembly reads: positions and velocities of every particle at its start.
  struct AssemblyInput {
    const Vec3* position;
    const Vec3* velocity;
    Vec3 gravity;
    Scalar timeStep;  ///< h
  };
  /// What assemble() writes for each particle of its range.
  struct AssemblyOutput {
    /// Its mass times gravity, then plus each spring's force on it (from its end, with damping),
    /// in the order of its incidence row: particleForce()'s sum without the pressure.
    Vec3* force;
    /// Nine per particle, column-major: m·I + Σ S over its springs, in row order.
    Scalar* diagonal;
    /// Three per slot, one array each: h²·K_s·(v_other − v_i) of the slot's spring.
    Scalar* velocityTermX;
    Scalar* velocityTermY;
    Scalar* velocityTermZ;
  };
  /// Sets the block S = (h·c + h²·k·(1 − t))·d̂d̂ᵀ + h²·k·t·I (t = max(0, 1 − L/|d|)) of every slot
  /// of the particles in [begin, end) from the state, and writes their outputs. A spring of zero
  /// or non-finite length has a zero block (and, like computeSpringForces(), a zero force at zero
  /// length). `begin` is a multiple of kLanes. Outputs of pinned particles are written but mean
  /// nothing: their rows are empty.
  void assemble(const AssemblyInput& input, const AssemblyOutput& output, std::size_t begin,
                std::size_t end);

  /// product[i] = (A·x)_i for the particles in [begin, end), zero where `inverseMass` is zero;
  /// returns Σ x_i·(A·x)_i over them in double, summed in particle order. `begin` is a multiple of
  /// kLanes; x has paddedSize() entries.
  double multiply(const Vec3* x, Vec3* product, const Scalar* inverseMass, std::size_t begin,
                  std::size_t end) const;

 private:
  friend struct SlicedSpringMatrixKernel;

  std::vector<Index> sliceStart_;  ///< per slice, its first slot; one more at the end
  std::vector<Index> neighbour_;   ///< per slot, the other end (the zero entry if pinned or none)
  std::vector<std::size_t> springSlot_;  ///< per spring, its slots at ends a and b
  std::vector<Scalar> axisX_, axisY_, axisZ_, along_, isotropic_;  ///< per slot, its block
  /// Per slot, its spring as seen from the row's particle, for assemble(): the other end (pinned
  /// or not; the particle itself in a padding slot), the rest length, stiffness and damping, and
  /// 1 where the slot holds a spring, 0 where it is padding.
  std::vector<Index> other_;
  std::vector<Scalar> restLength_, stiffness_, damping_, used_;
  std::vector<Scalar> laneMass_;  ///< the masses, padded with zeros to whole slices
  bool avx2_ = false;             ///< the processor runs AVX2
  bool gatherable_ = false;       ///< AVX2, and every vector's offset fits a gather's 32 bits
};

}  // namespace softbake
