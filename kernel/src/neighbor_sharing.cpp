// Neighbor lists shared between the pair forces of one system (see
// SharedNeighborList in pdyn/neighbors.hpp).
//
// Why sharing is safe. A list built with cutoff c and skin s, rebuilt when a
// particle has moved more than s / 2, holds at every call every pair closer
// than c (Verlet's argument), hence every pair closer than any c' <= c. A
// force with cutoff c' can therefore use the list of any force with a larger
// cutoff, whatever the skins; the shared list takes the largest cutoff and
// the largest reach (cutoff + skin) of its forces, so that its reach is one
// a force already asked for (and the box check of that force's factory
// already accepted).
//
// What is shared is found by key: the address of the positions array
// (every force of a System sees the System's own array, one per system; a
// copy of the state is another array), N, the box, the list kind and the
// member mask. An address can be reused by another system once the first is
// gone; its list is then still right (validity depends on the positions
// alone: NeighborList::update() checks them at every call), only shared.
//
// A rebuild schedule (RebuildSchedule, LAMMPS's neigh_modify) is kept by
// the same key: the host names the step under way by its start time, and
// each shared list counts the steps since its own last build.
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "pdyn/kernel/neighbor_schedule.hpp"
#include "pdyn/neighbors.hpp"

namespace pdyn {

struct SharedNeighborList::Entry {
  const double* x = nullptr;
  Index n = 0;
  Domain domain;
  NeighborList::Kind kind = NeighborList::Kind::Half;
  std::vector<std::uint8_t> mask;  // empty: every particle
  double cutoff = 0, reach = 0;    // the largest asked for, m
  NeighborList list;
  // Under a rebuild schedule: the start time of the last step this list
  // counted, and the steps counted since its last build.
  double step_time = std::numeric_limits<double>::quiet_NaN();
  std::int64_t ago = 0;
  // A barostat's box: the domain of the list's last build and the largest
  // move of its faces since (NeighborList::UpdateRule::box_moved).
  Domain built_in;
  double box_moved = 0.0;
  // Under MPI ranks (set_neighbor_ghosts): the member mask the list is
  // built with, 2 marking a ghost member, and the ghosts' generation it
  // was made from (0: none).
  std::vector<std::uint8_t> with_ghosts;
  std::uint64_t ghost_generation = 0;

  Entry(const double* x_, Index n_, const Domain& d, NeighborList::Kind k,
        const std::vector<std::uint8_t>* members, double c, double s)
      : x(x_),
        n(n_),
        domain(d),
        kind(k),
        mask(members ? *members : std::vector<std::uint8_t>{}),
        cutoff(c),
        reach(c + s),
        list(c, s, k) {}

  // The same list's memory for other particles of the same kind, as new
  // but for its buffers (a System whose arrays were reallocated, as an MPI
  // rank's at each exchange of particles): it rebuilds at its next update
  // without allocating what it had.
  void rebind(const double* x_, Index n_, const Domain& d, const std::vector<std::uint8_t>* members,
              double c, double s) {
    x = x_;
    n = n_;
    domain = d;
    mask = members ? *members : std::vector<std::uint8_t>{};
    cutoff = c;
    reach = c + s;
    list.set_range(c, s);
    step_time = std::numeric_limits<double>::quiet_NaN();
    ago = 0;
    built_in = Domain{};
    box_moved = 0.0;
    with_ghosts.clear();
    ghost_generation = 0;
  }

  bool matches(const double* x_, Index n_, const Domain& d, NeighborList::Kind k,
               const std::vector<std::uint8_t>* members) const {
    if (x != x_ || n != n_ || kind != k || !NeighborList::resizes(domain, d)) return false;
    return members ? mask == *members : mask.empty();
  }
};

namespace {

// Every live shared list of the process. Looked up only when a force meets
// particles other than those of its last call (its first call, a system that
// grew), so the lock is not on the per-step path.
struct Registry {
  std::mutex mutex;
  std::vector<std::weak_ptr<SharedNeighborList::Entry>> entries;
};

Registry& registry() {
  static Registry r;
  return r;
}

// The rebuild schedules the host gave, by positions array, with the start
// time of the step under way. Most processes have none, and then update()
// takes no lock for them.
struct StepClock {
  RebuildSchedule schedule;
  double time = 0.0;
};
struct Schedules {
  std::mutex mutex;
  std::vector<std::pair<const double*, StepClock>> clocks;
  std::atomic<bool> any{false};
};

Schedules& schedules() {
  static Schedules s;
  return s;
}

std::optional<StepClock> clock_of(const double* x) {
  Schedules& s = schedules();
  if (!s.any.load(std::memory_order_acquire)) return std::nullopt;
  const std::lock_guard lock(s.mutex);
  for (const auto& [key, clock] : s.clocks) {
    if (key == x) return clock;
  }
  return std::nullopt;
}

// The ghosts a host named per positions array (set_neighbor_ghosts), each
// with a generation that changes at every call; `any` spares the lookup
// when no host named any.
struct Ghosts {
  std::mutex mutex;
  std::atomic<bool> any{false};
  std::uint64_t last = 0;
  std::map<const double*, std::pair<std::uint64_t, std::vector<std::uint8_t>>> of;
};

Ghosts& ghosts() {
  static Ghosts g;
  return g;
}

// The member mask of a list on `x` of n particles under ghosts: the force's
// own members (or all), a ghost member marked 2 (NeighborList drops pairs
// of two). Remade only when the ghosts' generation changed, and then
// `renamed` is set: the host has exchanged the particles, so that index i
// may be another particle even where N and the mask are unchanged, and the
// list must be rebuilt. `members` as given without ghosts for x.
const std::vector<std::uint8_t>* with_ghosts(SharedNeighborList::Entry& e, const double* x, Index n,
                                             const std::vector<std::uint8_t>* members,
                                             bool& renamed) {
  Ghosts& g = ghosts();
  if (!g.any.load(std::memory_order_acquire)) return members;
  const std::lock_guard lock(g.mutex);
  const auto it = g.of.find(x);
  if (it == g.of.end() || static_cast<Index>(it->second.second.size()) != n) return members;
  if (e.ghost_generation != it->second.first) {
    e.ghost_generation = it->second.first;
    renamed = true;
    const auto& ghost = it->second.second;
    e.with_ghosts.resize(ghost.size());
    for (std::size_t i = 0; i < ghost.size(); ++i) {
      const bool member = members == nullptr || (*members)[i] != 0;
      e.with_ghosts[i] = member ? (ghost[i] != 0 ? 2 : 1) : 0;
    }
  }
  return &e.with_ghosts;
}

// LAMMPS's Neighbor::decide(): a step counts once; at a decision step the
// list rebuilds always (check no) or if a particle moved beyond skin / 2.
NeighborList::Rebuild decide(SharedNeighborList::Entry& e, const StepClock& clock) {
  if (clock.time == e.step_time) return NeighborList::Rebuild::IfForced;
  e.step_time = clock.time;
  ++e.ago;
  const RebuildSchedule& s = clock.schedule;
  if (e.ago < s.delay || e.ago % s.every != 0) return NeighborList::Rebuild::IfForced;
  return s.check ? NeighborList::Rebuild::IfMoved : NeighborList::Rebuild::Always;
}

}  // namespace

void begin_neighbor_step(const double* x, double t, const RebuildSchedule& schedule) {
  if (schedule.every < 1 || schedule.delay < 0) {
    throw std::invalid_argument(fmt::format(
        "neighbor rebuild schedule: every = {}, delay = {} (expected every >= 1, delay >= 0)",
        schedule.every, schedule.delay));
  }
  Schedules& s = schedules();
  const std::lock_guard lock(s.mutex);
  auto it =
      std::find_if(s.clocks.begin(), s.clocks.end(), [&](const auto& c) { return c.first == x; });
  if (schedule == RebuildSchedule{}) {
    if (it != s.clocks.end()) s.clocks.erase(it);
  } else if (it == s.clocks.end()) {
    s.clocks.emplace_back(x, StepClock{schedule, t});
  } else {
    it->second = StepClock{schedule, t};
  }
  s.any.store(!s.clocks.empty(), std::memory_order_release);
}

void set_neighbor_ghosts(const double* x, const std::uint8_t* ghost, std::int64_t n) {
  Ghosts& g = ghosts();
  const std::lock_guard lock(g.mutex);
  if (ghost == nullptr) {
    g.of.erase(x);
  } else {
    g.of[x] = {++g.last, std::vector<std::uint8_t>(ghost, ghost + n)};
  }
  g.any.store(!g.of.empty(), std::memory_order_release);
}

SharedNeighborList::SharedNeighborList(double cutoff, double skin, NeighborList::Kind kind)
    : cutoff_(cutoff), skin_(skin), kind_(kind) {
  [[maybe_unused]] const NeighborList checked(cutoff, skin, kind);  // its checks and messages
}

const NeighborList* SharedNeighborList::list() const noexcept {
  return entry_ ? &entry_->list : nullptr;
}

const NeighborList& SharedNeighborList::update(const Eigen::Ref<const Matrix3X>& x,
                                               const Domain& domain,
                                               const std::vector<std::uint8_t>* members) {
  const double* key = x.data();
  const Index n = x.cols();
  if (!entry_ || !entry_->matches(key, n, domain, kind_, members)) {
    Registry& r = registry();
    const std::lock_guard lock(r.mutex);
    std::erase_if(r.entries, [](const auto& e) { return e.expired(); });
    std::shared_ptr<Entry> old = std::move(entry_);
    for (const auto& weak : r.entries) {
      auto live = weak.lock();
      if (live && live->matches(key, n, domain, kind_, members)) {
        entry_ = std::move(live);
        break;
      }
    }
    if (!entry_ && old && old.use_count() == 1) {  // no other force shares it
      old->rebind(key, n, domain, members, cutoff_, skin_);
      entry_ = std::move(old);
    } else if (!entry_) {
      entry_ = std::make_shared<Entry>(key, n, domain, kind_, members, cutoff_, skin_);
      r.entries.push_back(entry_);
    }
  }
  Entry& e = *entry_;
  if (cutoff_ > e.cutoff || cutoff_ + skin_ > e.reach) {
    e.cutoff = std::max(e.cutoff, cutoff_);
    e.reach = std::max(e.reach, cutoff_ + skin_);
    e.list.set_range(e.cutoff, e.reach - e.cutoff);
  }
  NeighborList::UpdateRule rule;
  if (const auto clock = clock_of(key)) rule.when = decide(e, *clock);
  // A list built before stays while only the periodic faces moved: the
  // faces' largest move since the build shrinks what particles may move.
  const double moved =
      e.list.size() == n && NeighborList::resizes(e.built_in, domain)
          ? (domain.min - e.built_in.min).norm() + (domain.max - e.built_in.max).norm()
          : 0.0;
  rule.box_moved = std::max(e.box_moved, moved);
  bool renamed = false;
  const std::vector<std::uint8_t>* mask = with_ghosts(e, key, n, members, renamed);
  if (renamed) rule.when = NeighborList::Rebuild::Always;
  if (e.list.update(x, domain, mask, rule)) {
    e.ago = 0;
    e.built_in = domain;
    e.box_moved = 0.0;
  } else {
    e.box_moved = rule.box_moved;
  }
  return e.list;
}

}  // namespace pdyn
