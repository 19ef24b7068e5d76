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
#include <algorithm>
#include <mutex>

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

  bool matches(const double* x_, Index n_, const Domain& d, NeighborList::Kind k,
               const std::vector<std::uint8_t>* members) const {
    if (x != x_ || n != n_ || kind != k || !(domain == d)) return false;
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

}  // namespace

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
    entry_.reset();
    for (const auto& weak : r.entries) {
      auto live = weak.lock();
      if (live && live->matches(key, n, domain, kind_, members)) {
        entry_ = std::move(live);
        break;
      }
    }
    if (!entry_) {
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
  e.list.update(x, domain, members);
  return e.list;
}

}  // namespace pdyn
