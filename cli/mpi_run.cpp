// `pdyn run` on several MPI ranks (cli/mpi_launch.hpp; docs/parallel.md):
// MPI_Init, the scene decomposed (pdyn/host/decomposed.hpp), rank 0 running
// run_scene on its copy of the whole scene while the others follow.
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
  ~OpenMpiRun() override {
    decomposed_.reset();
    MPI_Finalize();
  }
  OpenMpiRun(const OpenMpiRun&) = delete;
  OpenMpiRun& operator=(const OpenMpiRun&) = delete;

  int rank() const override { return rank_; }

  RunResult run(Scene& local, Scene* whole, RunOptions options, const std::string& grid,
                std::ostream& err) override {
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::optional<RankGrid> g;
    if (!grid.empty()) g = parse_rank_grid(grid, ranks);
    decomposed_ = std::make_unique<DecomposedSystem>(MPI_COMM_WORLD, local, g);
    local_ = &local;
    evaluations_before_ = local.system->force_evaluations();
    running_ = true;
    const std::int64_t k0 = options.resume ? options.resume->step : 0;
    RunResult result;
    if (whole != nullptr) {
      MpiRankDriver driver(*decomposed_);
      options.ranks = &driver;
      result = run_scene(*whole, options);
    } else {
      result.exit_code = follow_run(*decomposed_, k0, options.threads, err);
    }
    running_ = false;
    return result;
  }

  std::uint64_t evaluations() const override {
    return local_ != nullptr ? local_->system->force_evaluations() - evaluations_before_ : 0;
  }

  void abort_if_running(int status) override {
    if (running_) MPI_Abort(MPI_COMM_WORLD, status);
  }

 private:
  int rank_ = 0;
  std::unique_ptr<DecomposedSystem> decomposed_;
  Scene* local_ = nullptr;
  std::uint64_t evaluations_before_ = 0;
  bool running_ = false;
};

}  // namespace

std::unique_ptr<MpiRun> start_mpi_run() { return std::make_unique<OpenMpiRun>(); }

}  // namespace pdyn::cli
