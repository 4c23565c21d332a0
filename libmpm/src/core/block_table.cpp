#include <mpm/core/block_table.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <numeric>

namespace mpm {

KeyOrder sort_keys(const std::vector<BlockKey>& keys) {
  const std::size_t n = keys.size();
  KeyOrder result;
  // Chunks of at least 2^16 keys, a few per thread.
  const std::size_t threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  std::size_t chunks = std::clamp<std::size_t>(n >> 16, 1, 4 * threads);
  const auto chunk_range = [&](std::size_t c) { return std::pair{n * c / chunks, n * (c + 1) / chunks}; };
  const auto for_chunks = [&](auto&& f) {
    if (chunks == 1) return f(std::size_t{0});
    tbb::parallel_for(std::size_t{0}, chunks, f);
  };

  // The distinct keys of each chunk, then of all, ascending; and whether the keys are sorted.
  std::vector<std::vector<BlockKey>> distinct(chunks);
  std::vector<char> sorted(chunks, 1);
  for_chunks([&](std::size_t c) {
    const auto [first, last] = chunk_range(c);
    std::vector<BlockKey>& d = distinct[c];
    for (std::size_t i = first; i < last; ++i) {
      if (i > first && keys[i] == keys[i - 1]) continue;
      if (i > 0 && keys[i] < keys[i - 1]) sorted[c] = 0;
      d.push_back(keys[i]);
    }
    std::sort(d.begin(), d.end());
    d.erase(std::unique(d.begin(), d.end()), d.end());
  });
  for (const std::vector<BlockKey>& d : distinct) result.key.insert(result.key.end(), d.begin(), d.end());
  tbb::parallel_sort(result.key.begin(), result.key.end());  // as long as n for scattered keys
  result.key.erase(std::unique(result.key.begin(), result.key.end()), result.key.end());
  const std::size_t k = result.key.size();
  BlockTable rank;
  rank.reset(k);
  for (std::size_t r = 0; r < k; ++r) rank.insert(result.key[r], static_cast<int>(r));
  result.identity = std::all_of(sorted.begin(), sorted.end(), [](char s) { return s != 0; });
  // The counts cost chunks x ranks: at most about n (one chunk when every key is distinct).
  chunks = std::clamp<std::size_t>(n / std::max<std::size_t>(k, 1), 1, chunks);

  // Each chunk's count per rank (chunk-major), turned into the first place of its keys of
  // that rank: after the keys of lower ranks and after the earlier chunks' keys of this rank.
  std::vector<std::uint32_t> key_rank(n);
  std::vector<std::uint32_t> place(chunks * k, 0);
  for_chunks([&](std::size_t c) {
    const auto [first, last] = chunk_range(c);
    std::uint32_t* count = place.data() + c * k;
    for (std::size_t i = first; i < last; ++i) {
      key_rank[i] =
          i > first && keys[i] == keys[i - 1] ? key_rank[i - 1] : static_cast<std::uint32_t>(rank.find(keys[i]));
      ++count[key_rank[i]];
    }
  });
  result.begin.resize(k + 1);
  std::uint32_t next = 0;
  for (std::size_t r = 0; r < k; ++r) {
    result.begin[r] = next;
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::uint32_t count = place[c * k + r];
      place[c * k + r] = next;
      next += count;
    }
  }
  result.begin[k] = next;
  if (result.identity) return result;
  result.order.resize(n);
  for_chunks([&](std::size_t c) {
    const auto [first, last] = chunk_range(c);
    std::uint32_t* at = place.data() + c * k;
    for (std::size_t i = first; i < last; ++i) result.order[at[key_rank[i]]++] = static_cast<std::uint32_t>(i);
  });
  return result;
}

std::vector<std::uint32_t> stable_key_order(const std::vector<BlockKey>& keys) {
  KeyOrder sorted = sort_keys(keys);
  if (sorted.identity) {
    sorted.order.resize(keys.size());
    std::iota(sorted.order.begin(), sorted.order.end(), std::uint32_t{0});
  }
  return std::move(sorted.order);
}

}  // namespace mpm
