#include "core/dynamics/sliced_spring_matrix.hpp"

#include <algorithm>
#include <cstring>

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
  for (Index i = 0; i < n; ++i) {
    laneMass_[i] = topology.mass[i];
    for (Index k = 0; k < rowLength(i); ++k) {
      const Index ref = topology.springRefs[topology.springRowStart[i] + k];
      const Spring& spring = topology.springs[ref >> 1];
      const Index other = (ref & 1) ? spring.a : spring.b;
      if (topology.inverseMass[other] != 0) neighbour_[slot(i, k)] = other;
      springSlot_[2 * (ref >> 1) + (ref & 1)] = slot(i, k);
    }
  }
  useAvx2(true);
}

void SlicedSpringMatrix::useAvx2(bool on) {
#if defined(__x86_64__)
  avx2_ = on && __builtin_cpu_supports("avx2");
#else
  (void)on;
  avx2_ = false;
#endif
}

struct SlicedSpringMatrixKernel {
  /// The product over [begin, end), compiled once per instruction set: inlined into each caller,
  /// it takes that caller's target.
  [[gnu::always_inline]] static inline double multiply(const SlicedSpringMatrix& matrix,
                                                       const Vec3* x, Vec3* product,
                                                       const Scalar* inverseMass, std::size_t begin,
                                                       std::size_t end) {
    constexpr std::size_t kLanes = SlicedSpringMatrix::kLanes;
    // A slice's lanes side by side in one value (the vector extensions of GCC and clang): each
    // operation acts lane by lane.
    using Lanes = Scalar __attribute__((vector_size(kLanes * sizeof(Scalar))));
    const auto load = [](Lanes& lanes, const Scalar* from) {
      std::memcpy(&lanes, from, sizeof lanes);
    };
    static_assert(sizeof(Vec3) == 3 * sizeof(Scalar), "a Vec3 is its three coordinates");
    const Scalar* coordinates = x->data();  // gathered by index, three at a time
    const Index* neighbour = matrix.neighbour_.data();
    double curvature = 0;
    for (std::size_t first = begin; first < end; first += kLanes) {
      // Every lane of a gathered value is written before it is read; the braces say so to GCC.
      Lanes inX{}, inY{}, inZ{}, mass, ax, ay, az, along, isotropic;
      for (std::size_t l = 0; l < kLanes; ++l) {
        const Scalar* in = coordinates + 3 * (first + l);
        inX[l] = in[0], inY[l] = in[1], inZ[l] = in[2];
      }
      load(mass, &matrix.laneMass_[first]);
      Lanes sumX = mass * inX, sumY = mass * inY, sumZ = mass * inZ;
      const std::size_t slice = first / kLanes;
      for (std::size_t e = std::size_t(matrix.sliceStart_[slice]) * kLanes;
           e < std::size_t(matrix.sliceStart_[slice + 1]) * kLanes; e += kLanes) {
        Lanes otherX{}, otherY{}, otherZ{};
        for (std::size_t l = 0; l < kLanes; ++l) {
          const Scalar* other = coordinates + 3 * std::size_t(neighbour[e + l]);
          otherX[l] = other[0], otherY[l] = other[1], otherZ[l] = other[2];
        }
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
  [[gnu::target("avx2")]] static double multiplyAvx2(const SlicedSpringMatrix& matrix,
                                                     const Vec3* x, Vec3* product,
                                                     const Scalar* inverseMass, std::size_t begin,
                                                     std::size_t end) {
    return multiply(matrix, x, product, inverseMass, begin, end);
  }
#endif
  static double multiplyBaseline(const SlicedSpringMatrix& matrix, const Vec3* x, Vec3* product,
                                 const Scalar* inverseMass, std::size_t begin, std::size_t end) {
    return multiply(matrix, x, product, inverseMass, begin, end);
  }
};

double SlicedSpringMatrix::multiply(const Vec3* x, Vec3* product, const Scalar* inverseMass,
                                    std::size_t begin, std::size_t end) const {
#if defined(__x86_64__)
  if (avx2_)
    return SlicedSpringMatrixKernel::multiplyAvx2(*this, x, product, inverseMass, begin, end);
#endif
  return SlicedSpringMatrixKernel::multiplyBaseline(*this, x, product, inverseMass, begin, end);
}

}  // namespace softbake
