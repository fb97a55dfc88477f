#pragma once
// One table for a pair of enumerations that mean the same thing (a core enum and its IDL
// twin), read in both directions: the conversions to and from messages are written once,
// and a value missing from the table is an answer (nullopt), not a silent default.

#include <array>
#include <cstddef>
#include <optional>
#include <utility>

namespace concert {

template <class A, class B, std::size_t N>
class EnumMap {
 public:
  constexpr explicit EnumMap(std::array<std::pair<A, B>, N> pairs) : pairs_(pairs) {}

  /// The B paired with `a`; nullopt if the table has no row for it.
  constexpr std::optional<B> to(A a) const {
    for (const auto& [x, y] : pairs_) {
      if (x == a) return y;
    }
    return std::nullopt;
  }
  /// The A paired with `b` (the first row that has it); nullopt if none.
  constexpr std::optional<A> from(B b) const {
    for (const auto& [x, y] : pairs_) {
      if (y == b) return x;
    }
    return std::nullopt;
  }
  constexpr const std::array<std::pair<A, B>, N>& pairs() const { return pairs_; }

 private:
  std::array<std::pair<A, B>, N> pairs_;
};

template <class A, class B, std::size_t N>
EnumMap(std::array<std::pair<A, B>, N>) -> EnumMap<A, B, N>;

}  // namespace concert
