// The viewer's wire protocol (docs/viewer.md, "WebSocket protocol"): binary
// frames of float32 positions from server to page, JSON commands from page to
// server. Pure functions, no networking, so that tests check every byte.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "pdyn/types.hpp"

namespace pdyn::viewer {

/// Version of the protocol; the page checks it in the `scene` message.
inline constexpr int kProtocolVersion = 1;
/// First four bytes of a binary frame: "PDYF" read as a little-endian u32.
inline constexpr std::uint32_t kFrameMagic = 0x46594450;
/// Bytes before the positions (six 4- and 8-byte fields, see docs/viewer.md).
inline constexpr std::size_t kFrameHeaderBytes = 48;
/// Largest command a client may send, bytes: a command is a few numbers.
inline constexpr std::size_t kMaxCommandBytes = 64 * 1024;

/// What one frame carries.
struct Frame {
  std::uint32_t topology = 0;  ///< the scene message these positions belong to
  double time = 0.0;           ///< s
  std::uint64_t step = 0;      ///< steps since the scene was (re)loaded
  bool playing = false;
  double kinetic = 0.0;          ///< J
  double potential = 0.0;        ///< J
  std::vector<float> positions;  ///< x0 y0 z0 x1 ..., m (3N)
  std::vector<float> speeds;     ///< |v_i|, m/s (N)
};

/// The frame as the bytes of one binary WebSocket message (little-endian).
std::string encode_frame(const Frame& frame);
/// The inverse, for tests and tools. Throws ProtocolError on a short or
/// inconsistent message.
Frame decode_frame(std::string_view in);

/// A message a client sent is not a command: the text goes back to it in an
/// `error` message.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One command from a page (docs/viewer.md, "Client to server"). Fields a
/// command does not take are left empty.
struct Command {
  enum class Op {
    Play,
    Pause,
    Step,
    Reset,
    Reload,
    Speed,
    Solver,
    Dt,
    Drag,
    Move,
    Release,
    Nail,
    Create,
    Attach
  };
  Op op = Op::Play;
  std::string op_name;            ///< as sent, for replies
  std::optional<Index> id, a, b;  ///< particle indices (>= 0; range checked by the session)
  std::optional<Vec3> point;      ///< m
  std::optional<double> value;    ///< speed (1) or dt (s)
  std::optional<double> mass;     ///< kg
  std::optional<double> ks, kd;   ///< N/m, N s/m
  std::string name;               ///< solver name
};

/// Parses one text message. Throws ProtocolError saying what is wrong and
/// what was expected: too long, not JSON, not an object, no or unknown
/// `op`, a missing field, a field of the wrong type, a number out of range.
Command parse_command(std::string_view text);

/// `{"type":"error","op":OP|null,"message":MESSAGE}`.
std::string error_message(std::string_view op, std::string_view message);
/// `{"type":"ack","op":OP}` or, with `id`, `{"type":"ack","op":OP,"id":ID}`.
std::string ack_message(std::string_view op, std::optional<Index> id = std::nullopt);

}  // namespace pdyn::viewer
