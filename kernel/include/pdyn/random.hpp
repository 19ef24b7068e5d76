// pdyn/random.hpp — counter-based random numbers, for forces that draw noise
// (a Langevin thermostat) and hosts that draw initial velocities.
//
// A counter-based generator (Salmon, Moraes, Dror & Shaw 2011, "Parallel
// random numbers: as easy as 1, 2, 3", SC'11; Philox4x64-10 from the
// Random123 library) is a keyed bijection of a counter: the numbers for
// (seed, stream, step, particle) are the same whichever thread asks, in
// whatever order, and after a resume from a checkpoint, with no generator
// state to carry or to split between threads. pdyn uses it so that noisy
// runs stay bit-identical for any thread count, as every other run is.
//
//   const pdyn::Vec3 xi = pdyn::standard_normal3({seed, kMyStream}, step, i);
#pragma once

#include <cstdint>

#include "pdyn/export.hpp"
#include "pdyn/types.hpp"

namespace pdyn {

/// Which numbers: a user's seed and a stream that tells apart the users of
/// one seed (a plugin picks a constant of its own, so that two plugins given
/// the same seed draw independent numbers).
struct PDYN_API RandomKey {
  std::uint64_t seed = 0;
  std::uint64_t stream = 0;
};

/// The streams pdyn's own users draw from.
namespace random_stream {
inline constexpr std::uint64_t kVelocities =
    0x76656c6f63697479;                                         ///< "velocity": scene `velocities:`
inline constexpr std::uint64_t kLangevin = 0x6c616e676576696e;  ///< "langevin": the langevin force
}  // namespace random_stream

/// Three independent standard normal deviates (mean 0, variance 1) for the
/// counter (step, i): Philox4x64-10, then the Box-Muller transform (Random123's
/// boxmuller). `step` is any 64-bit number naming the draw (a step index, or
/// the bits of the step's start time), `i` the particle.
PDYN_API Vec3 standard_normal3(const RandomKey& key, std::uint64_t step, std::uint64_t i);

/// Four independent uniform deviates in (0, 1] for the counter (step, i),
/// from the same generator.
PDYN_API Eigen::Vector4d uniform4(const RandomKey& key, std::uint64_t step, std::uint64_t i);

}  // namespace pdyn
