// `pdyn run` on several MPI ranks (cli/mpi_launch.hpp; docs/parallel.md):
// MPI_Init, the scene decomposed (pdyn/host/decomposed.hpp), rank 0 running
// run_scene on its copy of the whole scene while the others follow.
#include <fmt/format.h>
#include <mpi.h>

#include <ostream>

#include "mpi_launch.hpp"
#include "pdyn/host/decomposed.hpp"
#include "pdyn/system.hpp"

namespace pdyn::cli {

namespace {

class OpenMpiRun final : public MpiRun {
 public:
  OpenMpiRun() {
    MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  }
  ~OpenMpiRun() override { MPI_Finalize(); }
  OpenMpiRun(const OpenMpiRun&) = delete;
  OpenMpiRun& operator=(const OpenMpiRun&) = delete;

  int rank() const override { return rank_; }

  RunResult run(Scene& local, const std::function<Scene()>* load_whole, std::optional<Scene>& whole,
                RunOptions options, const std::string& grid, std::ostream& err) override {
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::optional<RankGrid> g;
    if (!grid.empty()) g = parse_rank_grid(grid, ranks);
    // Within this call: it refers to `local`, which the caller owns.
    DecomposedSystem decomposed(MPI_COMM_WORLD, local, g);
    const std::uint64_t evaluations_before = local.system->force_evaluations();
    running_ = true;
    const std::int64_t k0 = options.resume ? options.resume->step : 0;
    RunResult result;
    if (load_whole != nullptr) {
      whole.emplace((*load_whole)());
      MpiRankDriver driver(decomposed);
      options.ranks = &driver;
      result = run_scene(*whole, options);
    } else {
      result.exit_code = follow_run(decomposed, k0, options.threads, err);
    }
    running_ = false;
    evaluations_ = local.system->force_evaluations() - evaluations_before;
    const RankGrid& used = decomposed.halo().decomposition().grid();
    summary_ = fmt::format(
        "pdyn: {} MPI ranks on a {} x {} x {} grid, {} exchanges of particles; rank 0 holds {} "
        "particles and sends {} ghost copies per force evaluation",
        ranks, used.n[0], used.n[1], used.n[2], decomposed.exchanges(), decomposed.halo().owned(),
        decomposed.halo().ghosts_sent());
    return result;
  }

  std::uint64_t evaluations() const override { return evaluations_; }
  std::string summary() const override { return summary_; }

  void abort_if_running(int status) override {
    if (running_) MPI_Abort(MPI_COMM_WORLD, status);
  }

 private:
  int rank_ = 0;
  std::uint64_t evaluations_ = 0;
  std::string summary_;
  bool running_ = false;
};

}  // namespace

std::unique_ptr<MpiRun> start_mpi_run() { return std::make_unique<OpenMpiRun>(); }

}  // namespace pdyn::cli
