// One rank's owned particles and ghosts under MPI (pdyn/host/halo.hpp).
#include "pdyn/host/halo.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "pdyn/error.hpp"

namespace pdyn {

namespace {

// Displacements of consecutive groups of `count` elements.
std::vector<int> offsets_of(const std::vector<int>& count) {
  std::vector<int> offset(count.size(), 0);
  std::exclusive_scan(count.begin(), count.end(), offset.begin(), 0);
  return offset;
}

Vec3 place(const ParticleRecord& r) { return {r.place[0], r.place[1], r.place[2]}; }

bool by_id(const ParticleRecord& a, const ParticleRecord& b) { return a.id < b.id; }

// Sorts `v`, made of consecutive runs of run[r] elements each, by `less`:
// merges the runs pairwise when each is sorted already (as every rank sends
// its particles, in increasing id), O(n log runs); sorts it otherwise.
template <class T, class Less>
void merge_runs(std::vector<T>& v, const std::vector<int>& run, Less less) {
  std::vector<std::size_t> bound{0};
  for (const int n : run) bound.push_back(bound.back() + static_cast<std::size_t>(n));
  const auto at = [&](std::size_t k) { return v.begin() + static_cast<std::ptrdiff_t>(k); };
  for (std::size_t r = 0; r + 1 < bound.size(); ++r) {
    if (!std::is_sorted(at(bound[r]), at(bound[r + 1]), less)) {
      std::sort(v.begin(), v.end(), less);
      return;
    }
  }
  while (bound.size() > 2) {
    std::vector<std::size_t> merged{0};
    for (std::size_t r = 0; r + 1 < bound.size(); r += 2) {
      const std::size_t end = std::min(r + 2, bound.size() - 1);
      std::inplace_merge(at(bound[r]), at(bound[r + 1]), at(bound[end]), less);
      merged.push_back(bound[end]);
    }
    bound = std::move(merged);
  }
}

}  // namespace

Halo::Halo(MPI_Comm comm, Decomposition decomposition)
    : comm_(comm), decomposition_(std::move(decomposition)) {
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &ranks_);
  if (decomposition_.grid().ranks() != ranks_) {
    throw Error(fmt::format("a grid of {} subdomains for {} ranks (expected one per rank)",
                            decomposition_.grid().ranks(), ranks_));
  }
  // Records travel as bytes of one type, so that counts are particles (an
  // int of bytes would overflow at 27 million particles per rank pair).
  MPI_Type_contiguous(static_cast<int>(sizeof(ParticleRecord)), MPI_BYTE, &record_type_);
  MPI_Type_commit(&record_type_);
}

Halo::~Halo() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && record_type_ != MPI_DATATYPE_NULL) MPI_Type_free(&record_type_);
}

void Halo::alltoall(const std::vector<ParticleRecord>& out, const std::vector<int>& count,
                    std::vector<int>& in_count, std::vector<ParticleRecord>& in) const {
  in_count.assign(static_cast<std::size_t>(ranks_), 0);
  MPI_Alltoall(count.data(), 1, MPI_INT, in_count.data(), 1, MPI_INT, comm_);
  const std::vector<int> out_offset = offsets_of(count), in_offset = offsets_of(in_count);
  in.resize(static_cast<std::size_t>(in_offset.back()) + static_cast<std::size_t>(in_count.back()));
  MPI_Alltoallv(out.data(), count.data(), out_offset.data(), record_type_, in.data(),
                in_count.data(), in_offset.data(), record_type_, comm_);
}

void Halo::migrate(const std::vector<ParticleRecord>& held) {
  // Each particle that left this rank's subdomain goes to its new owner,
  // grouped by destination with a stable counting sort; the others stay,
  // in the order held (between two exchanges few particles move on). The
  // buffers are kept: a melt's rank exchanges megabytes of records every
  // few steps, and fresh pages cost more than the copies.
  std::vector<int> count(static_cast<std::size_t>(ranks_), 0);
  std::vector<ParticleRecord>& owned = owned_scratch_;
  owned.clear();
  std::vector<std::pair<int, std::size_t>> movers;  // (destination, index in held)
  for (std::size_t i = 0; i < held.size(); ++i) {
    const int dest = decomposition_.owner(place(held[i]));
    if (dest == rank_) {
      owned.push_back(held[i]);
    } else {
      movers.emplace_back(dest, i);
      ++count[static_cast<std::size_t>(dest)];
    }
  }
  std::vector<int> next = offsets_of(count);
  out_scratch_.resize(movers.size());
  for (const auto& [dest, i] : movers)
    out_scratch_[static_cast<std::size_t>(next[static_cast<std::size_t>(dest)]++)] = held[i];
  std::vector<int> in_count;
  alltoall(out_scratch_, count, in_count, in_scratch_);
  std::vector<int> runs{static_cast<int>(owned.size())};
  runs.insert(runs.end(), in_count.begin(), in_count.end());
  owned.insert(owned.end(), in_scratch_.begin(), in_scratch_.end());
  merge_runs(owned, runs, by_id);
}

std::vector<int> Halo::send_ghosts(std::vector<std::vector<std::size_t>>& to) {
  // A copy of each owned particle to every rank within reach, in increasing
  // id per destination (owned_scratch_ is sorted).
  const std::vector<ParticleRecord>& owned = owned_scratch_;
  to.assign(static_cast<std::size_t>(ranks_), {});
  std::vector<int> ranks;
  for (std::size_t i = 0; i < owned.size(); ++i) {
    ranks.clear();
    decomposition_.ghost_ranks(place(owned[i]), rank_, ranks);
    for (const int r : ranks) to[static_cast<std::size_t>(r)].push_back(i);
  }
  std::vector<int> count(to.size(), 0);
  out_scratch_.clear();
  for (std::size_t r = 0; r < to.size(); ++r) {
    count[r] = static_cast<int>(to[r].size());
    for (const std::size_t i : to[r]) out_scratch_.push_back(owned[i]);
  }
  std::vector<int> in_count;
  alltoall(out_scratch_, count, in_count, in_scratch_);
  return in_count;
}

void Halo::exchange(const std::vector<ParticleRecord>& held) {
  migrate(held);
  std::vector<std::vector<std::size_t>> to;
  std::vector<int> runs = send_ghosts(to);
  const std::vector<ParticleRecord>& owned = owned_scratch_;
  const std::vector<ParticleRecord>& ghosts = in_scratch_;

  // The local order: owned and ghosts merged by id. Where each owned
  // particle and each arriving ghost lands gives forward()'s maps.
  local_.clear();
  local_.reserve(owned.size() + ghosts.size());
  ghost_.assign(owned.size() + ghosts.size(), 0);
  auto& order = order_scratch_;  // (id, source): source < 0 owned
  order.clear();
  for (std::size_t i = 0; i < owned.size(); ++i)
    order.emplace_back(owned[i].id, -1 - static_cast<std::int64_t>(i));
  for (std::size_t g = 0; g < ghosts.size(); ++g)
    order.emplace_back(ghosts[g].id, static_cast<std::int64_t>(g));
  runs.insert(runs.begin(), static_cast<int>(owned.size()));
  merge_runs(order, runs, std::less<>());
  std::vector<Index> owned_local(owned.size());
  recv_local_.assign(ghosts.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::int64_t source = order[k].second;
    if (k > 0 && order[k - 1].first == order[k].first) {
      throw Error(
          fmt::format("rank {}: particle {} arrived twice (each particle must be held by one rank)",
                      rank_, order[k].first));
    }
    if (source < 0) {
      owned_local[static_cast<std::size_t>(-1 - source)] = static_cast<Index>(k);
      local_.push_back(owned[static_cast<std::size_t>(-1 - source)]);
    } else {
      recv_local_[static_cast<std::size_t>(source)] = static_cast<Index>(k);
      local_.push_back(ghosts[static_cast<std::size_t>(source)]);
      ghost_[k] = 1;
    }
  }
  owned_ = static_cast<Index>(owned.size());

  // forward()'s plan: the same groups, in doubles.
  send_local_.clear();
  send_count_.assign(to.size(), 0);
  for (std::size_t r = 0; r < to.size(); ++r) {
    send_count_[r] = 6 * static_cast<int>(to[r].size());
    for (const std::size_t i : to[r]) send_local_.push_back(owned_local[i]);
  }
  send_offset_ = offsets_of(send_count_);
  recv_count_.assign(to.size(), 0);
  MPI_Alltoall(send_count_.data(), 1, MPI_INT, recv_count_.data(), 1, MPI_INT, comm_);
  recv_offset_ = offsets_of(recv_count_);
}

void Halo::forward(Eigen::Ref<Matrix3X> x, Eigen::Ref<Matrix3X> v) const {
  // Buffers kept between calls: forward() runs at every force evaluation.
  std::vector<double>& out = send_buffer_;
  std::vector<double>& in = recv_buffer_;
  out.resize(6 * send_local_.size());
  in.resize(6 * recv_local_.size());
  for (std::size_t k = 0; k < send_local_.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      out[6 * k + static_cast<std::size_t>(a)] = x(a, send_local_[k]);
      out[6 * k + 3 + static_cast<std::size_t>(a)] = v(a, send_local_[k]);
    }
  }
  MPI_Alltoallv(out.data(), send_count_.data(), send_offset_.data(), MPI_DOUBLE, in.data(),
                recv_count_.data(), recv_offset_.data(), MPI_DOUBLE, comm_);
  for (std::size_t k = 0; k < recv_local_.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      x(a, recv_local_[k]) = in[6 * k + static_cast<std::size_t>(a)];
      v(a, recv_local_[k]) = in[6 * k + 3 + static_cast<std::size_t>(a)];
    }
  }
}

}  // namespace pdyn
