#include "output.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <utility>

#include "pdyn/host/registry.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/host/scene_drawables.hpp"
#include "pdyn/kernel/plugin_call.hpp"
#include "pdyn/output_file.hpp"

namespace pdyn {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Whether a writer with energies reads the virial (Output::Slot). The
// shipped energy writer does only for its pressure and virial columns; any
// other writer may read Frame::virial, so it always gets it.
bool reads_virial(const WriterSpec& spec) {
  if (spec.record.descriptor->name != "energy" || !spec.params.has("columns")) return true;
  const auto& columns = spec.params.strings("columns");
  return std::find_if(columns.begin(), columns.end(), [](const std::string& c) {
           return c == "pressure" || c == "virial";
         }) != columns.end();
}

}  // namespace

// ---------------------------------------------------------------------------
// OutputThread

OutputThread::OutputThread(std::function<void()> job)
    : job_(std::move(job)), thread_([this] { loop(); }) {}

OutputThread::~OutputThread() {
  {
    const std::lock_guard lock(mutex_);
    quit_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void OutputThread::start() {
  {
    const std::lock_guard lock(mutex_);
    busy_ = true;
  }
  cv_.notify_all();
}

void OutputThread::wait() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [&] { return !busy_; });
}

void OutputThread::loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait(lock, [&] { return busy_ || quit_; });
    if (busy_) {
      lock.unlock();
      job_();  // never throws: write_queued() catches every writer failure
      lock.lock();
      busy_ = false;
      cv_.notify_all();
    } else {
      return;  // quit_, with no job left
    }
  }
}

// ---------------------------------------------------------------------------
// Output

Output::Output(const Scene& scene, const Checkpoint* resume)
    : scene_(scene), sys_(*scene.system), checkpoint_(checkpoint_path(scene)) {
  const auto& specs = scene.output.writers;
  if (specs.empty()) return;
  WriterContext base(sys_.view());
  base.dt = scene.dt;
  for (const auto& use : scene.uses) {
    if (use.kind != PluginKind::Force) continue;
    for (const auto& entry : use.params.values()) {
      if (const auto* p = std::get_if<std::vector<IndexPair>>(&entry.second)) {
        base.pairs.insert(base.pairs.end(), p->begin(), p->end());
      } else if (const auto* t = std::get_if<std::vector<IndexTriple>>(&entry.second)) {
        base.triples.insert(base.triples.end(), t->begin(), t->end());
      }
    }
  }
  const Drawables d = drawables(scene);
  for (const auto& x : d.planes) base.obstacles.emplace_back(x);
  for (const auto& x : d.spheres) base.obstacles.emplace_back(x);
  for (const auto& x : d.boxes) base.obstacles.emplace_back(x);
  for (const auto& x : d.meshes) base.obstacles.emplace_back(x);
  for (const auto& spec : specs) {
    WriterContext ctx = base;
    ctx.path = spec.path;
    ctx.fields = spec.fields;
    ctx.every = spec.every;
    if (resume) {
      const WriterMark* m = resume->output(spec.path.string());
      if (!m) {
        throw CheckpointError(fmt::format(
            "{}: the checkpoint has no mark for this output (expected a checkpoint of a run "
            "that wrote it)",
            spec.path.string()));
      }
      ctx.resume = m->mark;
      ctx.resuming = true;
    }
    Slot slot;
    slot.spec = &spec;
    const auto& fields = spec.fields;
    slot.force = std::find(fields.begin(), fields.end(), field::kForce) != fields.end();
    slot.energy = spec.record.descriptor->writer_traits.energy;
    slot.constraint_virial = slot.energy && reads_virial(spec);
    try {
      const crash::CallScope call(spec.label, "create");
      slot.writer = create_writer(spec.record, spec.params, ctx);
    } catch (const ResumeError& e) {
      throw CheckpointError(e.what());
    } catch (const PluginError&) {
      throw;
    } catch (const std::exception& e) {
      throw PluginRuntimeError(
          spec.label, fmt::format("cannot start its output: {}{}", e.what(), library_of(spec)));
    }
    slots_.push_back(std::move(slot));
  }
}

Output::~Output() {
  // The output thread must be done with the writers before they go.
  thread_.reset();
}

bool Output::due(const Slot& s, std::int64_t n) {
  return s.spec->every > 0 && n % s.spec->every == 0;
}

void Output::emit_first(std::int64_t step) {
  dispatch(step, true, false, [](const Slot&) { return true; });
}

void Output::new_state() {
  for (auto& s : slots_) s.current = false;
}

void Output::emit(std::int64_t n, bool current) {
  dispatch(n, current, false, [n](const Slot& s) { return due(s, n); });
}

void Output::emit_extra(std::int64_t step) {
  bool any = false;
  for (auto& s : slots_) {
    if (s.current || s.failed) continue;
    if (!s.held) s.held = mark(s);  // waits for the frame being written
    any = true;
  }
  if (!any) return;
  dispatch(step, true, true, [](const Slot& s) { return !s.current && !s.failed; });
}

void Output::resume_at(const Checkpoint& c, std::int64_t n,
                       const std::function<bool(std::int64_t every)>& wrote) {
  for (auto& s : slots_) {
    const WriterMark* m = c.output(s.spec->path.string());
    if (!m) continue;
    // The frames the interrupted run could not write, before anything else.
    for (std::size_t k = 0; k < m->pending.size(); ++k) {
      if (s.failed) {
        s.pending.push_back(m->pending[k]);
        continue;
      }
      FrameSnapshot frame;
      try {
        frame = FrameSnapshot::decode(m->pending[k]);
      } catch (const Error& e) {
        throw CheckpointError(fmt::format("{}: {} (pending frame {} of {})", s.spec->path.string(),
                                          e.what(), k + 1, m->pending.size()));
      }
      std::string error = write_one(s, frame.frame(s.force, s.energy));
      if (!error.empty()) {
        s.failed = true;
        s.pending.push_back(m->pending[k]);
        if (failure_.empty()) failure_ = std::move(error);
      }
    }
  }
  for (auto& s : slots_) {
    const WriterMark* m = c.output(s.spec->path.string());
    s.current = m && m->wrote_state >= 0 ? m->wrote_state == 1 : wrote(s.spec->every);
  }
  if (n < 0) return;
  dispatch(n, true, false, [n](const Slot& s) { return !s.current && due(s, n); });
}

void Output::finish_frames() {
  if (!writing_) return;
  const auto t0 = Clock::now();
  thread_->wait();
  stalled_seconds_ += seconds_since(t0);
  writing_ = false;
  for (auto& s : slots_) {
    if (!s.queued) continue;
    s.queued = false;
    if (s.error.empty()) continue;
    s.failed = true;
    // An extra frame is not part of the output a resumed run continues.
    if (!s.queued_extra) s.pending.push_back(snapshot_.encode());
    if (failure_.empty()) failure_ = std::move(s.error);
    s.error.clear();
  }
}

void Output::dispatch(std::int64_t step, bool current, bool extra,
                      const std::function<bool(const Slot&)>& pick) {
  bool any = false, force = false, energy = false, virial = false;
  for (const auto& s : slots_) {
    if (!pick(s)) continue;
    any = true;
    force = force || s.force;
    energy = energy || s.energy;
    virial = virial || s.constraint_virial;
  }
  if (!any) return;
  finish_frames();  // the snapshot is free, and failures so far are known
  // The constraint forces' virial needs the applied forces at this state
  // (pdyn/thermo.hpp: total_virial(sys, solver, h)); an evaluation between
  // steps changes no bit of the run (pdyn/force_reuse.hpp).
  if (force || (virial && scene_.system->constraint_rows() > 0)) {
    scene_.system->compute_accelerations();
  }
  const auto t0 = Clock::now();
  snapshot_.capture(sys_, scene_.solver.get(), step, force, energy, scene_.dt, virial);
  stalled_seconds_ += seconds_since(t0);
  bool queued = false;
  for (auto& s : slots_) {
    if (!pick(s)) continue;
    if (current) s.current = true;
    if (s.failed) {
      if (!extra) s.pending.push_back(snapshot_.encode());
      continue;
    }
    s.queued = queued = true;
    s.queued_extra = extra;
  }
  if (!queued) return;
  if (!thread_) thread_ = std::make_unique<OutputThread>([this] { write_queued(); });
  writing_ = true;
  thread_->start();
}

void Output::write_queued() {
  const auto t0 = Clock::now();
  for (auto& s : slots_) {
    if (s.queued) s.error = write_one(s, snapshot_.frame(s.force, s.energy));
  }
  writing_seconds_ += seconds_since(t0);
}

std::string Output::write_one(Slot& s, const Frame& frame) {
  try {
    const crash::CallScope call(s.spec->label, "write");
    s.writer->write(frame);
    return {};
  } catch (const std::exception& e) {
    return fmt::format(
        "writer {} failed at step {}: {}{}; its output keeps the frames before this one",
        s.spec->label, frame.step, e.what(), library_of(*s.spec));
  } catch (...) {
    return fmt::format(
        "writer {} failed at step {}: write threw a non-standard exception{}; its output keeps "
        "the frames before this one",
        s.spec->label, frame.step, library_of(*s.spec));
  }
}

fs::path Output::write_checkpoint_now(std::int64_t step, std::int64_t next_frame, bool has_dense) {
  finish_frames();
  step_ = step;
  Checkpoint c = capture_checkpoint(scene_, step);
  c.next_frame = next_frame;
  c.has_dense = has_dense;
  for (auto& s : slots_) {
    auto m = s.held ? *s.held : mark(s);
    const bool wrote = s.current && !s.held;
    c.outputs.push_back(
        {s.spec->path.string(), std::move(m), static_cast<std::int8_t>(wrote), s.pending});
  }
  write_checkpoint(checkpoint_, c);
  // From now on the temporary files are what a resume continues.
  if (crash_report_) crash_report_->keep_temp_files(checkpoint_);
  return checkpoint_;
}

void Output::commit() {
  finish_frames();
  const auto t0 = Clock::now();
  std::exception_ptr first;
  for (auto& s : slots_) {
    try {
      const crash::CallScope call(s.spec->label, "commit");
      s.writer->commit();
    } catch (...) {
      // A writer that failed during the run has been reported already.
      if (!first && !s.failed) first = std::current_exception();
    }
  }
  // The writers' last flush, fsync and rename: writing time, and time the
  // run waits for.
  const double t = seconds_since(t0);
  writing_seconds_ += t;
  stalled_seconds_ += t;
  if (first) std::rethrow_exception(first);
}

std::vector<fs::path> Output::temp_files() const {
  std::vector<fs::path> files;
  for (const auto& s : slots_) {
    for (auto& f : s.writer->temp_files()) files.push_back(std::move(f));
  }
  return files;
}

std::string Output::library_of(const WriterSpec& spec) const {
  return fmt::format(" (library {})", spec.record.library.string());
}

// A writer whose mark() fails (its flush met a full disk) has failed:
// asked again, it gives the mark of its last complete output, which may
// not hold the current state.
std::vector<std::uint8_t> Output::mark(Slot& s) {
  finish_frames();
  const crash::CallScope call(s.spec->label, "mark");
  try {
    return s.writer->mark();
  } catch (const std::exception& e) {
    s.failed = true;
    s.current = false;
    if (failure_.empty()) {
      failure_ =
          fmt::format("writer {} failed at step {}: {}{}; its output keeps the frames it completed",
                      s.spec->label, step_, e.what(), library_of(*s.spec));
    }
    return s.writer->mark();
  }
}

}  // namespace pdyn
