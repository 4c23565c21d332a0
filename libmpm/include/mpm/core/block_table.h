#pragma once
//! A hash table from block key to storage slot whose memory follows the allocated blocks, not
//! the domain (SPGrid's aim, with open addressing instead of virtual memory): a grid whose
//! finest level spans 2^13 cells per axis in 3D holds a few bytes per allocated block.
//!
//! Open addressing with linear probing on a power-of-two table kept at most half full; keys
//! are never erased one by one (a grid replaces its whole allocated set), so no tombstones.
#include <algorithm>
#include <cstdint>
#include <vector>

namespace mpm {

//! Packed block coordinates (see SparseGrid::block_id); ~0 is never a valid key.
using BlockKey = std::uint64_t;

class BlockTable {
public:
  //! Empties the table and sizes it for `count` keys.
  void reset(std::size_t count) {
    std::size_t capacity = 16;
    int bits = 4;
    for (; capacity < 2 * count; capacity *= 2) ++bits;
    keys_.assign(capacity, kEmpty);
    values_.assign(capacity, -1);
    mask_ = capacity - 1;
    shift_ = 64 - bits;
    size_ = 0;
  }
  //! Inserts (key, value) unless the key is present; returns the stored value.
  int insert(BlockKey key, int value) {
    if (2 * (size_ + 1) > keys_.size()) grow();
    std::size_t i = home(key);
    while (keys_[i] != kEmpty) {
      if (keys_[i] == key) return values_[i];
      i = (i + 1) & mask_;
    }
    keys_[i] = key;
    values_[i] = value;
    ++size_;
    return value;
  }
  //! Overwrites the value of a present key (no effect when absent).
  void assign(BlockKey key, int value) {
    if (const std::size_t i = position(key); i != kNone) values_[i] = value;
  }
  //! The value stored for `key`, or -1.
  int find(BlockKey key) const {
    const std::size_t i = position(key);
    return i == kNone ? -1 : values_[i];
  }
  std::size_t size() const { return size_; }
  //! Calls fn(key, value) for every entry, in table order.
  template <class Fn>
  void for_each(Fn&& fn) const {
    for (std::size_t i = 0; i < keys_.size(); ++i)
      if (keys_[i] != kEmpty) fn(keys_[i], values_[i]);
  }
  std::size_t bytes() const { return keys_.capacity() * sizeof(BlockKey) + values_.capacity() * sizeof(int); }

private:
  static constexpr BlockKey kEmpty = ~BlockKey{0};
  static constexpr std::size_t kNone = ~std::size_t{0};

  //! Fibonacci hashing: the top bits of the product, which every bit of the key reaches (the
  //! last axis sits in the key's high bits).
  std::size_t home(BlockKey key) const { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }
  std::size_t position(BlockKey key) const {
    if (keys_.empty()) return kNone;
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return i;
      if (keys_[i] == kEmpty) return kNone;
    }
  }
  void grow() {
    std::vector<BlockKey> keys = std::move(keys_);
    std::vector<int> values = std::move(values_);
    reset(keys.empty() ? 8 : keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) insert(keys[i], values[i]);
  }

  std::vector<BlockKey> keys_;
  std::vector<int> values_;
  std::size_t mask_ = 0;
  int shift_ = 63;
  std::size_t size_ = 0;
};

//! A stable sort of block keys (particles by the block of their stencil).
struct KeyOrder {
  std::vector<std::uint32_t> order;  //!< the sorted sequence holds keys[order[0]], keys[order[1]], ...
  std::vector<BlockKey> key;         //!< the distinct keys, ascending
  std::vector<std::uint32_t> begin;  //!< where key[r] begins in the sorted sequence; begin.back() = n
  bool identity = false;             //!< the keys were sorted already (order is then empty)
};

//! The stable counting sort of `keys` by the rank of the keys present: O(n + k log k) for k
//! distinct keys (blocks are few against particles). In parallel over chunks of the keys (each
//! counts its keys per rank, then places them after the earlier chunks' keys of that rank); a
//! key equal to its predecessor reuses its rank without a lookup. A stable sort's result is
//! unique, so it does not depend on the thread count.
KeyOrder sort_keys(const std::vector<BlockKey>& keys);

//! The stable order that sorts `keys` (sort_keys' order, the identity when already sorted).
std::vector<std::uint32_t> stable_key_order(const std::vector<BlockKey>& keys);

}  // namespace mpm
