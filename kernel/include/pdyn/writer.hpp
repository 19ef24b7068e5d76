// pdyn/writer.hpp — output writers, the fourth plugin kind: each one turns
// frames of the particle system into files of its format (csv, vtk, h5md).
//
// The host owns the schedule: a writer is created once per run with the
// scene's `path`, `every` and `fields` (WriterContext), is handed a Frame
// every `every` steps (and the last state of a run that ends, is
// interrupted or fails between scheduled frames), and is committed at the
// end. What it writes must never be partial under its final name (write
// under a temporary name and rename: OutputFile in pdyn/output_file.hpp
// does it), and a resumed run must continue it exactly: mark() says how far
// the output went when a checkpoint is taken, and the host gives those bytes
// back in WriterContext::resume.
//
//   class Lines final : public pdyn::Writer {
//    public:
//     explicit Lines(const pdyn::WriterContext& ctx) : file_(ctx.path, ...) {}
//     void write(const pdyn::Frame& f) override { file_.write(fmt::format("{}\n", f.time())); }
//     std::vector<std::uint8_t> mark() override { return file_.mark().encode(); }
//     void commit() override { file_.commit(); }
//    private:
//     pdyn::OutputFile file_;
//   };
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/export.hpp"
#include "pdyn/particles.hpp"
#include "pdyn/plugin_object.hpp"
#include "pdyn/shape.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// The fields a scene may ask a writer for with `fields: [...]`, besides the
/// positions every frame has. A writer lists the ones it can write in
/// WriterTraits::fields.
namespace field {
inline constexpr const char* kVelocity = "velocity";  ///< v, m/s
inline constexpr const char* kMass = "mass";          ///< m, kg
inline constexpr const char* kFixed = "fixed";        ///< 1 where nailed
inline constexpr const char* kRadius = "radius";      ///< m, where the scene gives radii
inline constexpr const char* kType = "type";    ///< particle type, where the scene gives types
inline constexpr const char* kForce = "force";  ///< total force f at the frame's state, N
inline constexpr const char* kImage = "image";  ///< periodic image counts (x + image L unwraps)
inline constexpr const char* kId = "id";        ///< particle index
}  // namespace field

/// Every field name the host knows, in the order above.
PDYN_API const std::vector<std::string>& known_fields();

/// One output time, as a writer sees it. Valid during write() only.
struct Frame {
  explicit Frame(ParticleView view) : particles(view) {}

  /// The step the frame belongs to: steps done for a fixed-step run; for an
  /// adaptive one the step a fixed-step run would write it at (t / dt),
  /// or the accepted steps done for the final or interrupted state.
  std::int64_t step = 0;
  /// t, x, v, mass, fixed, domain, radius and type of every particle.
  ParticleView particles;
  /// Per particle, box lengths it was wrapped by across periodic faces
  /// (unwrapped position x + image * L).
  std::span<const std::array<std::int32_t, 3>> images;
  /// Total force on each particle at this state (N, 3 x N), only when the
  /// writer was asked for the field "force"; nullptr otherwise.
  const Matrix3X* force = nullptr;
  /// Kinetic and potential energy (J) of the whole system, only for a
  /// writer whose traits ask for energy; 0 otherwise.
  double kinetic_energy = 0.0, potential_energy = 0.0;

  double time() const noexcept { return particles.t; }

  // Since pdyn 0.8.0, appended (a writer built against an earlier SDK reads
  // the members above where they always were). Like the energies, only for a
  // writer whose traits ask for energy.
  /// The virial W of every force (pdyn/thermo.hpp: total_virial), J; NaN
  /// when some force reports none, which `virial_missing` then names.
  double virial = 0.0;
  std::string_view virial_missing;
  /// The energy thermostats have taken out of the particles so far, J
  /// (pdyn/thermo.hpp: EnergyReservoir): kinetic + potential + this is
  /// conserved by a Nose-Hoover chain.
  double reservoir_energy = 0.0;

  // Since pdyn 0.10.0, appended likewise.
  /// The degrees of freedom the constraints remove (pdyn/thermo.hpp:
  /// constraint_dof, the independent rows), 0 without constraints: the
  /// temperature's N_f is 3 N_free - extra - constraint_dof. `virial` then
  /// includes the constraint forces' (total_virial(sys, solver, h)).
  double constraint_dof = 0.0;
  /// The part of potential_energy from bonded terms (forces implementing
  /// pdyn/bonded_reference.hpp: bonds, angles, dihedrals, impropers), J:
  /// LAMMPS's E_mol; the rest is E_pair and any other force's. Appended
  /// since pdyn 0.10.0.
  double bonded_energy = 0.0;
};

/// What a writer tells the host before it is created.
struct WriterTraits {
  /// The fields it can write (from field::); a scene asking for another is
  /// refused at load time.
  std::vector<std::string> fields;
  /// The fields written when the scene gives no `fields:`.
  std::vector<std::string> default_fields;
  /// Frames carry the kinetic and potential energy (a force evaluation's
  /// worth of work per frame).
  bool energy = false;
};

/// Everything a writer is created with, besides its own parameters.
struct WriterContext {
  explicit WriterContext(ParticleView view) : particles(view) {}

  /// The scene's `path:` (relative to the working folder), checked at load
  /// time: not a folder, not another output's or an input's file.
  std::filesystem::path path;
  /// The fields to write: the scene's `fields:` (each one of the writer's
  /// traits.fields) or the writer's default_fields.
  std::vector<std::string> fields;
  std::int64_t every = 1;  ///< a frame every `every` steps (0: first and final only)
  double dt = 0.0;         ///< the scene's time step, s
  /// The particles as the run starts (a resumed run: as the checkpoint has them).
  ParticleView particles;
  /// Particle pairs that forces join (springs and every other force's
  /// IndexPairs parameter), for a writer that draws them as lines.
  std::vector<IndexPair> pairs;
  /// Particle triples that forces join (angles, areas), for polygons.
  std::vector<IndexTriple> triples;
  /// The obstacles of the colliders that describe their shape (pdyn/shape.hpp).
  std::vector<Shape> obstacles;
  /// Empty for a new run. For a resumed one: what mark() returned when the
  /// checkpoint was written; the writer continues its output from there
  /// (throwing pdyn::ResumeError, pdyn/output_file.hpp, if it cannot).
  std::vector<std::uint8_t> resume;
  bool resuming = false;  ///< true when resume holds a mark (which may be empty)
};

/// One frame as a writer's reader gives it back (WriterReader).
struct FrameRecord {
  double time = 0.0;  ///< s
  Matrix3X x;         ///< positions, m (3 x N)
  Matrix3X v;         ///< velocities, m/s (3 x N); empty when the format holds none
};

/// A writer's optional reader of its own output: every frame in `path`
/// (the writer's path), in order. `pdyn check` compares them bit for bit
/// with the frames it wrote. Throws pdyn::Error if the output is unreadable.
using WriterReader = std::function<std::vector<FrameRecord>(const std::filesystem::path& path)>;

class PDYN_API Writer : public PluginObject {
 public:
  /// Writes one frame. Throws pdyn::Error naming the file on failure (a full
  /// disk): the run then stops, keeping what was committed to the marks.
  virtual void write(const Frame& frame) = 0;
  /// How far the output has gone, in the writer's own format: stored in a
  /// checkpoint and given back in WriterContext::resume. Everything written
  /// so far must be on disk (flushed) when it returns.
  virtual std::vector<std::uint8_t> mark() = 0;
  /// Completes the output: afterwards it is under its final name(s), whole.
  /// A writer destroyed without commit() removes its temporary files.
  virtual void commit() = 0;
  /// Temporary files being written (kept and named when a run crashes
  /// after a checkpoint, since a resumed run continues them).
  virtual std::vector<std::filesystem::path> temp_files() const { return {}; }
};

}  // namespace pdyn
