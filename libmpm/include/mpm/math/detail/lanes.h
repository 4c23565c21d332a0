#pragma once
//! Four doubles operated on together (math::svd3 of four matrices at once, math/svd.h): the
//! same expressions as on one double, in two SSE2 registers where the target has them. The
//! point is not only width: a 3x3 SVD is a latency chain of square roots and divisions, and
//! four independent chains in flight keep the divider and the multipliers busy. Masks hold
//! all-ones or all-zero lanes; `select` blends by bits, so a lane's result never depends on
//! another lane's and equals the result of the same expressions on one double.
#include <cmath>
#include <cstdint>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mpm::math::detail {

//! Two doubles, the width of an SSE2 register (GCC/Clang vector extension).
using Pair = double __attribute__((vector_size(16)));
using PairMask = std::int64_t __attribute__((vector_size(16)));

struct LaneMask {
  PairMask lo, hi;
  friend LaneMask operator&(LaneMask a, LaneMask b) { return {a.lo & b.lo, a.hi & b.hi}; }
  friend LaneMask operator|(LaneMask a, LaneMask b) { return {a.lo | b.lo, a.hi | b.hi}; }
  friend LaneMask operator~(LaneMask a) { return {~a.lo, ~a.hi}; }
};

//! Four lanes of doubles; lane l is (l < 2 ? lo : hi)[l % 2].
struct Lanes {
  Pair lo, hi;

  Lanes() = default;
  Lanes(double x) : lo{x, x}, hi{x, x} {}  // NOLINT: broadcast, as for a scalar
  Lanes(Pair l, Pair h) : lo(l), hi(h) {}

  double get(int lane) const { return lane < 2 ? lo[lane] : hi[lane - 2]; }
  void set(int lane, double x) { (lane < 2 ? lo[lane] : hi[lane - 2]) = x; }

  friend Lanes operator+(Lanes a, Lanes b) { return {a.lo + b.lo, a.hi + b.hi}; }
  friend Lanes operator-(Lanes a, Lanes b) { return {a.lo - b.lo, a.hi - b.hi}; }
  friend Lanes operator*(Lanes a, Lanes b) { return {a.lo * b.lo, a.hi * b.hi}; }
  friend Lanes operator/(Lanes a, Lanes b) { return {a.lo / b.lo, a.hi / b.hi}; }
  friend Lanes operator-(Lanes a) { return {-a.lo, -a.hi}; }
  Lanes& operator+=(Lanes b) { return *this = *this + b; }
  Lanes& operator-=(Lanes b) { return *this = *this - b; }
  friend LaneMask operator<(Lanes a, Lanes b) { return {a.lo < b.lo, a.hi < b.hi}; }
  friend LaneMask operator<=(Lanes a, Lanes b) { return {a.lo <= b.lo, a.hi <= b.hi}; }
  friend LaneMask operator>(Lanes a, Lanes b) { return {a.lo > b.lo, a.hi > b.hi}; }
  friend LaneMask operator>=(Lanes a, Lanes b) { return {a.lo >= b.lo, a.hi >= b.hi}; }
};

// The operations the SVD needs beyond arithmetic, on one double (mask: bool) and on Lanes.
inline double select(bool take_first, double a, double b) { return take_first ? a : b; }
inline bool any(bool m) { return m; }
inline bool negate(bool m) { return !m; }
inline double lane_abs(double x) { return std::abs(x); }
inline double lane_sqrt(double x) { return std::sqrt(x); }
inline double lane_copysign(double magnitude, double sign) { return std::copysign(magnitude, sign); }

inline Pair blend(PairMask m, Pair a, Pair b) {
  return reinterpret_cast<Pair>((reinterpret_cast<PairMask>(a) & m) | (reinterpret_cast<PairMask>(b) & ~m));
}
inline Lanes select(LaneMask m, Lanes a, Lanes b) { return {blend(m.lo, a.lo, b.lo), blend(m.hi, a.hi, b.hi)}; }
inline bool any(LaneMask m) { return ((m.lo[0] | m.lo[1]) | (m.hi[0] | m.hi[1])) != 0; }
inline LaneMask negate(LaneMask m) { return ~m; }

inline constexpr std::int64_t kSignBit = std::int64_t{1} << 63;

inline Pair pair_abs(Pair x) { return reinterpret_cast<Pair>(reinterpret_cast<PairMask>(x) & ~kSignBit); }
inline Lanes lane_abs(Lanes x) { return {pair_abs(x.lo), pair_abs(x.hi)}; }

inline Pair pair_copysign(Pair magnitude, Pair sign) {
  return reinterpret_cast<Pair>((reinterpret_cast<PairMask>(magnitude) & ~kSignBit) |
                                (reinterpret_cast<PairMask>(sign) & kSignBit));
}
inline Lanes lane_copysign(Lanes magnitude, Lanes sign) {
  return {pair_copysign(magnitude.lo, sign.lo), pair_copysign(magnitude.hi, sign.hi)};
}

//! IEEE square root per lane (correctly rounded: the same as std::sqrt on each lane).
inline Pair pair_sqrt(Pair x) {
#if defined(__SSE2__)
  return reinterpret_cast<Pair>(_mm_sqrt_pd(reinterpret_cast<__m128d>(x)));
#else
  return Pair{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}
inline Lanes lane_sqrt(Lanes x) { return {pair_sqrt(x.lo), pair_sqrt(x.hi)}; }

template <class T>
inline constexpr bool kOneLane = std::is_same_v<T, double>;

}  // namespace mpm::math::detail
