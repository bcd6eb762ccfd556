#include "core/dynamics/sliced_spring_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace softbake {

SlicedSpringMatrix::SlicedSpringMatrix(const SceneTopology& topology) {
  const Index n = topology.particleCount();
  const std::size_t slices = (std::size_t(n) + kLanes - 1) / kLanes;
  auto rowLength = [&](Index i) {
    return topology.inverseMass[i] == 0
               ? Index(0)
               : topology.springRowStart[i + 1] - topology.springRowStart[i];
  };
  sliceStart_.assign(slices + 1, 0);
  for (std::size_t slice = 0; slice < slices; ++slice) {
    Index width = 0;
    for (Index i = Index(slice * kLanes); i < std::min<std::size_t>(n, (slice + 1) * kLanes); ++i)
      width = std::max(width, rowLength(i));
    sliceStart_[slice + 1] = sliceStart_[slice] + width;
  }
  const std::size_t slots = std::size_t(sliceStart_.back()) * kLanes;
  neighbour_.assign(slots, n);  // padding reads the zero entry, through a zero block
  for (std::vector<Scalar>* numbers : {&axisX_, &axisY_, &axisZ_, &along_, &isotropic_})
    numbers->assign(slots, 0);
  laneMass_.assign(slices * kLanes, 0);
  springSlot_.assign(2 * topology.springs.size(), kNoSlot);
  other_.resize(slots);  // a padding slot joins its particle to itself (the last one, past the end)
  for (std::size_t slice = 0; slice < slices; ++slice)
    for (std::size_t e = std::size_t(sliceStart_[slice]) * kLanes;
         e < std::size_t(sliceStart_[slice + 1]) * kLanes; ++e)
      other_[e] = Index(std::min<std::size_t>(slice * kLanes + e % kLanes, n - 1));
  for (std::vector<Scalar>* numbers : {&restLength_, &stiffness_, &damping_, &used_})
    numbers->assign(slots, 0);
  for (Index i = 0; i < n; ++i) {
    laneMass_[i] = topology.mass[i];
    for (Index k = 0; k < rowLength(i); ++k) {
      const Index ref = topology.springRefs[topology.springRowStart[i] + k];
      const Spring& spring = topology.springs[ref >> 1];
      const Index other = (ref & 1) ? spring.a : spring.b;
      const std::size_t at = slot(i, k);
      if (topology.inverseMass[other] != 0) neighbour_[at] = other;
      springSlot_[2 * (ref >> 1) + (ref & 1)] = at;
      other_[at] = other;
      restLength_[at] = spring.restLength;
      stiffness_[at] = spring.stiffness;
      damping_[at] = spring.damping;
      used_[at] = 1;
    }
  }
  useAvx2(true);
}

void SlicedSpringMatrix::useAvx2(bool on) {
#if defined(__x86_64__)
  avx2_ = on && __builtin_cpu_supports("avx2");
  // The gather instructions take 32-bit signed offsets: 3·index must fit.
  gatherable_ = avx2_ && 3 * (laneMass_.size() + 1) <= std::size_t(INT32_MAX);
#else
  (void)on;
  avx2_ = false;
#endif
}

struct SlicedSpringMatrixKernel {
  /// A slice's lanes side by side in one value (the vector extensions of GCC and clang): each
  /// operation acts lane by lane.
  using Lanes = Scalar __attribute__((vector_size(SlicedSpringMatrix::kLanes * sizeof(Scalar))));

  [[gnu::always_inline]] static inline void load(Lanes& lanes, const Scalar* from) {
    std::memcpy(&lanes, from, sizeof lanes);
  }
  [[gnu::always_inline]] static inline void store(Scalar* to, const Lanes& lanes) {
    std::memcpy(to, &lanes, sizeof lanes);
  }
  /// The coordinates of vector indexOf(l) of `vectors` (three scalars each) into lane l.
  template <class IndexOf>
  [[gnu::always_inline]] static inline void gather(const Scalar* vectors, const IndexOf& indexOf,
                                                   Lanes& x, Lanes& y, Lanes& z) {
    for (std::size_t l = 0; l < SlicedSpringMatrix::kLanes; ++l) {
      const Scalar* vector = vectors + 3 * std::size_t(indexOf(l));
      x[l] = vector[0], y[l] = vector[1], z[l] = vector[2];
    }
  }

#if defined(__x86_64__)
  /// gather() of the vectors index[0..kLanes) in AVX2's gather instructions: three instructions
  /// where the loop takes 24 inserts, which were most of the product's time. The same loads, so
  /// the same result.
  template <class S>
  [[gnu::target("avx2")]] static inline void gatherAvx2(const S* vectors, const Index* index,
                                                        Lanes& x, Lanes& y, Lanes& z) {
    static_assert(std::is_same_v<S, float> && sizeof(Index) == 4, "8 lanes of 32 bits");
    __m256i offset;
    std::memcpy(&offset, index, sizeof offset);
    offset = _mm256_add_epi32(_mm256_add_epi32(offset, offset), offset);  // 3·index
    const __m256 gx = _mm256_i32gather_ps(vectors, offset, sizeof(float));
    const __m256 gy = _mm256_i32gather_ps(vectors + 1, offset, sizeof(float));
    const __m256 gz = _mm256_i32gather_ps(vectors + 2, offset, sizeof(float));
    std::memcpy(&x, &gx, sizeof x), std::memcpy(&y, &gy, sizeof y), std::memcpy(&z, &gz, sizeof z);
  }
#endif

  /// gather() of the vectors index[0..kLanes): in AVX2's gather instructions where kAvx2 (single
  /// precision only; a double-precision build keeps the loop).
  template <bool kAvx2, class S>
  [[gnu::always_inline]] static inline void gatherAt(const S* vectors, const Index* index, Lanes& x,
                                                     Lanes& y, Lanes& z) {
#if defined(__x86_64__)
    if constexpr (kAvx2 && std::is_same_v<S, float>) {
      gatherAvx2(vectors, index, x, y, z);
      return;
    }
#endif
    gather(
        vectors, [&](std::size_t l) { return index[l]; }, x, y, z);
  }

  /// The product over [begin, end), compiled once per instruction set: inlined into each caller,
  /// it takes that caller's target.
  template <bool kAvx2>
  [[gnu::always_inline]] static inline double multiply(const SlicedSpringMatrix& matrix,
                                                       const Vec3* x, Vec3* product,
                                                       const Scalar* inverseMass, std::size_t begin,
                                                       std::size_t end) {
    constexpr std::size_t kLanes = SlicedSpringMatrix::kLanes;
    static_assert(sizeof(Vec3) == 3 * sizeof(Scalar), "a Vec3 is its three coordinates");
    const Scalar* coordinates = x->data();  // gathered by index, three at a time
    const Index* neighbour = matrix.neighbour_.data();
    double curvature = 0;
    for (std::size_t first = begin; first < end; first += kLanes) {
      // Every lane of a gathered value is written before it is read; the braces say so to GCC.
      Lanes inX{}, inY{}, inZ{}, mass, ax, ay, az, along, isotropic;
      gather(
          coordinates, [&](std::size_t l) { return first + l; }, inX, inY, inZ);
      load(mass, &matrix.laneMass_[first]);
      Lanes sumX = mass * inX, sumY = mass * inY, sumZ = mass * inZ;
      const std::size_t slice = first / kLanes;
      for (std::size_t e = std::size_t(matrix.sliceStart_[slice]) * kLanes;
           e < std::size_t(matrix.sliceStart_[slice + 1]) * kLanes; e += kLanes) {
        Lanes otherX{}, otherY{}, otherZ{};
        gatherAt<kAvx2>(coordinates, neighbour + e, otherX, otherY, otherZ);
        const Lanes dx = inX - otherX, dy = inY - otherY, dz = inZ - otherZ;
        load(ax, &matrix.axisX_[e]), load(ay, &matrix.axisY_[e]), load(az, &matrix.axisZ_[e]);
        load(along, &matrix.along_[e]), load(isotropic, &matrix.isotropic_[e]);
        // S·d = α·(d̂·d)·d̂ + β·d, the dot of three summed as Eigen sums it (the last two first),
        // so that the result is the one of S's Eigen form.
        const Lanes a = along * (ax * dx + (ay * dy + az * dz));
        sumX += a * ax + isotropic * dx;
        sumY += a * ay + isotropic * dy;
        sumZ += a * az + isotropic * dz;
      }
      for (std::size_t l = 0; l < kLanes && first + l < end; ++l) {
        const std::size_t i = first + l;
        if (inverseMass[i] == 0) {  // the constraint filter: pinned rows are zero
          product[i].setZero();
          continue;
        }
        product[i] = Vec3(sumX[l], sumY[l], sumZ[l]);
        curvature += double(x[i].x()) * product[i].x() + double(x[i].y()) * product[i].y() +
                     double(x[i].z()) * product[i].z();
      }
    }
    return curvature;
  }

#if defined(__x86_64__)
  [[gnu::target("avx2"), gnu::flatten]] static double multiplyAvx2(const SlicedSpringMatrix& matrix,
                                                                   const Vec3* x, Vec3* product,
                                                                   const Scalar* inverseMass,
                                                                   std::size_t begin,
                                                                   std::size_t end) {
    return matrix.gatherable_ ? multiply<true>(matrix, x, product, inverseMass, begin, end)
                              : multiply<false>(matrix, x, product, inverseMass, begin, end);
  }
#endif
  static double multiplyBaseline(const SlicedSpringMatrix& matrix, const Vec3* x, Vec3* product,
                                 const Scalar* inverseMass, std::size_t begin, std::size_t end) {
    return multiply<false>(matrix, x, product, inverseMass, begin, end);
  }

  /// Lane-wise square root. The file is compiled with -fno-math-errno (core/CMakeLists.txt), so
  /// this loop becomes one square-root instruction per register of the caller's instruction set.
  [[gnu::always_inline]] static inline void takeSquareRoot(Lanes& value) {
    for (std::size_t l = 0; l < SlicedSpringMatrix::kLanes; ++l) value[l] = std::sqrt(value[l]);
  }

  /// The assembly over [begin, end): the spring loop and the particle loop of a step in one pass
  /// over the slices. Every operation is the one of the scalar formulas (springForceOnA(), the
  /// block S, Eigen's 3-term dot x₀y₀ + (x₁y₁ + x₂y₂)), lane by lane, so each particle's numbers
  /// are those of its row walked alone.
  template <bool kAvx2>
  [[gnu::always_inline]] static inline void assemble(SlicedSpringMatrix& matrix,
                                                     const SlicedSpringMatrix::AssemblyInput& in,
                                                     const SlicedSpringMatrix::AssemblyOutput& out,
                                                     std::size_t begin, std::size_t end) {
    constexpr std::size_t kLanes = SlicedSpringMatrix::kLanes;
    const Scalar* positions = in.position->data();
    const Scalar* velocities = in.velocity->data();
    const Index* other = matrix.other_.data();
    const Scalar h = in.timeStep, h2 = h * h;
    const Lanes zero{};
    for (std::size_t first = begin; first < end; first += kLanes) {
      Lanes x{}, y{}, z{}, vx{}, vy{}, vz{};
      // Lanes past the end repeat the last particle.
      const auto particle = [&](std::size_t l) { return std::min(first + l, end - 1); };
      gather(positions, particle, x, y, z);
      gather(velocities, particle, vx, vy, vz);
      Lanes mass;
      load(mass, &matrix.laneMass_[first]);
      Lanes fx = mass * in.gravity.x(), fy = mass * in.gravity.y(), fz = mass * in.gravity.z();
      // m·I, entry by entry as Eigen's Identity() * m gives it.
      Lanes d00 = mass, d11 = mass, d22 = mass;
      Lanes d01 = mass * Scalar(0), d02 = d01, d10 = d01, d12 = d01, d20 = d01, d21 = d01;
      const std::size_t slice = first / kLanes;
      for (std::size_t e = std::size_t(matrix.sliceStart_[slice]) * kLanes;
           e < std::size_t(matrix.sliceStart_[slice + 1]) * kLanes; e += kLanes) {
        Lanes ox{}, oy{}, oz{}, ovx{}, ovy{}, ovz{};
        gatherAt<kAvx2>(positions, other + e, ox, oy, oz);
        gatherAt<kAvx2>(velocities, other + e, ovx, ovy, ovz);
        Lanes restLength, stiffness, damping, used;
        load(restLength, &matrix.restLength_[e]), load(stiffness, &matrix.stiffness_[e]);
        load(damping, &matrix.damping_[e]), load(used, &matrix.used_[e]);
        const auto inRow = used != zero;
        // springForceOnA() from this end: d = x_other − x_i.
        const Lanes dx = ox - x, dy = oy - y, dz = oz - z;
        Lanes length = dx * dx + (dy * dy + dz * dz);
        takeSquareRoot(length);
        const auto stretched = length > zero;
        Lanes ax = dx / length, ay = dy / length, az = dz / length;
        const Lanes dvx = ovx - vx, dvy = ovy - vy, dvz = ovz - vz;
        const Lanes axial =
            stiffness * (length - restLength) + damping * (dvx * ax + (dvy * ay + dvz * az));
        // Zero at zero length, as computeSpringForces() has it (NaN stays NaN).
        const auto noForce = length <= zero;
        fx = inRow ? fx + (noForce ? zero : axial * ax) : fx;
        fy = inRow ? fy + (noForce ? zero : axial * ay) : fy;
        fz = inRow ? fz + (noForce ? zero : axial * az) : fz;
        // The block, with the transverse factor t = max(0, 1 − L/l) as std::max has it.
        const Lanes shortfall = Scalar(1) - restLength / length;
        const Lanes transverse = zero < shortfall ? shortfall : zero;
        const Lanes alongStiffness = stiffness * (Scalar(1) - transverse);
        const Lanes isotropicStiffness = stiffness * transverse;
        const Lanes axialVelocity = alongStiffness * (ax * dvx + (ay * dvy + az * dvz));
        Lanes termX = h2 * (axialVelocity * ax + isotropicStiffness * dvx);
        Lanes termY = h2 * (axialVelocity * ay + isotropicStiffness * dvy);
        Lanes termZ = h2 * (axialVelocity * az + isotropicStiffness * dvz);
        Lanes along = h * damping + h2 * alongStiffness;
        Lanes isotropic = h2 * isotropicStiffness;
        ax = stretched ? ax : zero, ay = stretched ? ay : zero, az = stretched ? az : zero;
        along = stretched ? along : zero, isotropic = stretched ? isotropic : zero;
        termX = stretched ? termX : zero, termY = stretched ? termY : zero;
        termZ = stretched ? termZ : zero;
        store(&matrix.axisX_[e], ax), store(&matrix.axisY_[e], ay), store(&matrix.axisZ_[e], az);
        store(&matrix.along_[e], along), store(&matrix.isotropic_[e], isotropic);
        store(&out.velocityTermX[e], termX), store(&out.velocityTermY[e], termY);
        store(&out.velocityTermZ[e], termZ);
        // diagonal += α·d̂d̂ᵀ, entry (r, c) = (α·d̂_r)·d̂_c as Eigen's outer product has it; then
        // β on the diagonal.
        const Lanes alongX = along * ax, alongY = along * ay, alongZ = along * az;
        d00 = inRow ? d00 + alongX * ax : d00, d01 = inRow ? d01 + alongX * ay : d01;
        d02 = inRow ? d02 + alongX * az : d02, d10 = inRow ? d10 + alongY * ax : d10;
        d11 = inRow ? d11 + alongY * ay : d11, d12 = inRow ? d12 + alongY * az : d12;
        d20 = inRow ? d20 + alongZ * ax : d20, d21 = inRow ? d21 + alongZ * ay : d21;
        d22 = inRow ? d22 + alongZ * az : d22;
        d00 = inRow ? d00 + isotropic : d00, d11 = inRow ? d11 + isotropic : d11;
        d22 = inRow ? d22 + isotropic : d22;
      }
      for (std::size_t l = 0; l < kLanes && first + l < end; ++l) {
        const std::size_t i = first + l;
        out.force[i] = Vec3(fx[l], fy[l], fz[l]);
        Scalar* diagonal = out.diagonal + 9 * i;  // column-major
        diagonal[0] = d00[l], diagonal[1] = d10[l], diagonal[2] = d20[l];
        diagonal[3] = d01[l], diagonal[4] = d11[l], diagonal[5] = d21[l];
        diagonal[6] = d02[l], diagonal[7] = d12[l], diagonal[8] = d22[l];
      }
    }
  }

#if defined(__x86_64__)
  [[gnu::target("avx2"), gnu::flatten]] static void assembleAvx2(
      SlicedSpringMatrix& matrix, const SlicedSpringMatrix::AssemblyInput& in,
      const SlicedSpringMatrix::AssemblyOutput& out, std::size_t begin, std::size_t end) {
    if (matrix.gatherable_)
      assemble<true>(matrix, in, out, begin, end);
    else
      assemble<false>(matrix, in, out, begin, end);
  }
#endif
  static void assembleBaseline(SlicedSpringMatrix& matrix,
                               const SlicedSpringMatrix::AssemblyInput& in,
                               const SlicedSpringMatrix::AssemblyOutput& out, std::size_t begin,
                               std::size_t end) {
    assemble<false>(matrix, in, out, begin, end);
  }
};

void SlicedSpringMatrix::assemble(const AssemblyInput& input, const AssemblyOutput& output,
                                  std::size_t begin, std::size_t end) {
  if (begin >= end) return;
#if defined(__x86_64__)
  if (avx2_) return SlicedSpringMatrixKernel::assembleAvx2(*this, input, output, begin, end);
#endif
  SlicedSpringMatrixKernel::assembleBaseline(*this, input, output, begin, end);
}

double SlicedSpringMatrix::multiply(const Vec3* x, Vec3* product, const Scalar* inverseMass,
                                    std::size_t begin, std::size_t end) const {
#if defined(__x86_64__)
  if (avx2_)
    return SlicedSpringMatrixKernel::multiplyAvx2(*this, x, product, inverseMass, begin, end);
#endif
  return SlicedSpringMatrixKernel::multiplyBaseline(*this, x, product, inverseMass, begin, end);
}

}  // namespace softbake
