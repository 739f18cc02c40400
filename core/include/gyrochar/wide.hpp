#pragma once
// Exact 128-bit integers from two 64-bit words, for the exact counts path of the pyramid.
//
// Portable two-word arithmetic: 32-bit microcontrollers have no __int128, so every operation has
// a plain 64-bit implementation. Where the compiler offers a native 64x64->128 multiply it is
// used for speed; tests check both against each other. All functions are constexpr, O(1),
// allocation-free and cannot fail; wrap-around is modular (two's complement) by design.
#include <cstdint>

namespace gyrochar {

/// Signed 128-bit value in two's complement (modulo 2^128).
struct Int128 {
  std::uint64_t lo = 0;
  std::uint64_t hi = 0;
  friend constexpr bool operator==(Int128, Int128) = default;
};

/// Unsigned 128-bit value (sums of squares).
struct UInt128 {
  std::uint64_t lo = 0;
  std::uint64_t hi = 0;
  friend constexpr bool operator==(UInt128, UInt128) = default;
};

constexpr Int128 widen(std::int64_t v) {
  return {static_cast<std::uint64_t>(v), v < 0 ? ~std::uint64_t{0} : std::uint64_t{0}};
}

#if defined(__SIZEOF_INT128__)
__extension__ using native_u128 = unsigned __int128;
constexpr native_u128 native(Int128 a) { return static_cast<native_u128>(a.hi) << 64 | a.lo; }
constexpr Int128 from_native(native_u128 v) { return {static_cast<std::uint64_t>(v), static_cast<std::uint64_t>(v >> 64)}; }
#endif

constexpr Int128 operator+(Int128 a, Int128 b) {
#if defined(__SIZEOF_INT128__)
  return from_native(native(a) + native(b));
#endif
  const std::uint64_t lo = a.lo + b.lo;
  return {lo, a.hi + b.hi + (lo < a.lo ? 1u : 0u)};
}

constexpr Int128 operator-(Int128 a, Int128 b) {
#if defined(__SIZEOF_INT128__)
  return from_native(native(a) - native(b));
#endif
  const std::uint64_t lo = a.lo - b.lo;
  return {lo, a.hi - b.hi - (a.lo < b.lo ? 1u : 0u)};
}

/// Narrows to int64. Returns false (and leaves `out` unspecified) when v is out of int64 range.
constexpr bool narrow(Int128 v, std::int64_t& out) {
  out = static_cast<std::int64_t>(v.lo);
  return v.hi == (out < 0 ? ~std::uint64_t{0} : std::uint64_t{0});
}

/// Exact a*b, plain 64-bit arithmetic (four 32x32->64 partial products).
constexpr UInt128 mul_wide_portable(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a_lo = a & 0xffffffffu, a_hi = a >> 32;
  const std::uint64_t b_lo = b & 0xffffffffu, b_hi = b >> 32;
  const std::uint64_t ll = a_lo * b_lo, lh = a_lo * b_hi, hl = a_hi * b_lo, hh = a_hi * b_hi;
  const std::uint64_t mid = (ll >> 32) + (lh & 0xffffffffu) + (hl & 0xffffffffu);
  return {(mid << 32) | (ll & 0xffffffffu), hh + (lh >> 32) + (hl >> 32) + (mid >> 32)};
}

/// Exact a*b; uses the compiler's 128-bit multiply when it has one (same result, fewer instructions).
constexpr UInt128 mul_wide(std::uint64_t a, std::uint64_t b) {
#if defined(__SIZEOF_INT128__)
  __extension__ using u128 = unsigned __int128;
  const u128 p = static_cast<u128>(a) * b;
  return {static_cast<std::uint64_t>(p), static_cast<std::uint64_t>(p >> 64)};
#else
  return mul_wide_portable(a, b);
#endif
}

/// Exact a*b of two signed values.
constexpr Int128 mul_signed(std::int64_t a, std::int64_t b) {
#if defined(__SIZEOF_INT128__)
  __extension__ using i128 = __int128;
  __extension__ using u128 = unsigned __int128;
  const auto product = static_cast<u128>(static_cast<i128>(a) * b);
  return {static_cast<std::uint64_t>(product), static_cast<std::uint64_t>(product >> 64)};
#endif
  const auto ua = static_cast<std::uint64_t>(a), ub = static_cast<std::uint64_t>(b);
  const UInt128 m = mul_wide(a < 0 ? 0 - ua : ua, b < 0 ? 0 - ub : ub);
  const Int128 p{m.lo, m.hi};
  return (a < 0) != (b < 0) ? Int128{} - p : p;
}

/// Exact v*v (at most 2^126, so it always fits).
constexpr UInt128 square(std::int64_t v) {
  const Int128 p = mul_signed(v, v);
  return {p.lo, p.hi};
}

/// acc += v (modulo 2^128). Returns true when the sum wrapped past 2^128.
constexpr bool add_overflows(UInt128& acc, UInt128 v) {
  const bool carry = __builtin_add_overflow(acc.lo, v.lo, &acc.lo);
  const bool wrap_hi = __builtin_add_overflow(acc.hi, v.hi, &acc.hi);
  const bool wrap_carry = __builtin_add_overflow(acc.hi, std::uint64_t{carry}, &acc.hi);
  return wrap_hi | wrap_carry;
}

/// acc += v (modulo 2^128), for sums of squares below 2^126 each: returns the new high word, whose
/// top bit the caller ORs into a sticky flag. A sum can only wrap past 2^128 by first landing in
/// [2^127, 2^128) (each step is below 2^126), so the sticky bit flags every sum that reached 2^127.
constexpr std::uint64_t add_high_word(UInt128& acc, UInt128 v) {
  const bool carry = __builtin_add_overflow(acc.lo, v.lo, &acc.lo);
  acc.hi += v.hi + std::uint64_t{carry};
  return acc.hi;
}

/// a*k modulo 2^128 (two's complement, like the other operations).
constexpr Int128 mul_mod(Int128 a, std::int64_t k) {
  const auto uk = static_cast<std::uint64_t>(k);
  const UInt128 low = mul_wide(a.lo, uk);
  // k as 128 bits has the high word 0 or all ones, which contributes -a.lo to the high word.
  return {low.lo, low.hi + a.hi * uk - (k < 0 ? a.lo : 0)};
}

/// Nearest double to v within 1 ulp (two roundings at most; relative error <= 2^-52).
constexpr double to_double(UInt128 v) {
  return static_cast<double>(v.hi) * 18446744073709551616.0 + static_cast<double>(v.lo);
}

/// Nearest double to the signed value v within 1 ulp.
constexpr double to_double(Int128 v) {
  if (static_cast<std::int64_t>(v.hi) >= 0) return to_double(UInt128{v.lo, v.hi});
  const Int128 magnitude = Int128{} - v;
  return -to_double(UInt128{magnitude.lo, magnitude.hi});
}

}  // namespace gyrochar
