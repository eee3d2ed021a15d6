// Per-thread memo of tables collapsed over one parameter: the single-scattering tables summed
// over their Legendre phase terms at a given g, the multiple-scattering tables summed over
// bounces at a given albedo. A bake meets few distinct (g, albedo) values (one per medium: a
// medium's albedo and g do not depend on its density), so collapsing once turns a 32-term or
// 30-bounce sum per query into a 4-bin lookup. Media mixtures give continuous values: a thread
// that keeps missing stops collapsing and the callers fall back to the direct sums.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace freqlab {

class CollapseMemo {
  public:
    // An identity for a table's contents: addresses are reused after a table is destroyed,
    // so memo entries are keyed by this instead (copies share it: same contents).
    static uint64_t next_owner_id() {
        static std::atomic<uint64_t> next{1};
        return next++;
    }
    // The collapsed table for (owner, key), built by make() on a miss; null when this thread
    // misses too often for collapsing to pay.
    template <class Make>
    static const std::vector<double>* get(uint64_t owner, uint64_t key, Make&& make) {
        State& s = state();
        for (Slot& slot : s.slots)
            if (slot.owner == owner && slot.key == key && !slot.data.empty()) {
                ++s.hits;
                return &slot.data;
            }
        ++s.misses;
        if (s.misses > 64 && s.misses * 16 > s.hits) return nullptr;
        Slot& slot = s.slots[s.next++ % s.slots.size()];
        slot.owner = owner;
        slot.key = key;
        slot.data = make();
        return &slot.data;
    }

  private:
    struct Slot {
        uint64_t owner = 0;
        uint64_t key = 0;
        std::vector<double> data;
    };
    struct State {
        std::array<Slot, 8> slots;
        size_t next = 0;
        long hits = 0, misses = 0;
    };
    static State& state() {
        thread_local State s;
        return s;
    }
};

}  // namespace freqlab
