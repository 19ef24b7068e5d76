// Frame encoding and command parsing of the viewer protocol (docs/viewer.md).
#include "protocol.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

namespace pdyn::viewer {

namespace {

using nlohmann::json;

// The page reads frames with DataView and Float32Array, which are
// little-endian on every browser's platform; so is every machine pdyn
// builds on, but say so rather than assume it silently.
static_assert(std::endian::native == std::endian::little,
              "the frame encoding copies little-endian values as they are in memory");

template <class T>
void put(std::string& out, std::size_t at, T value) {
  std::memcpy(out.data() + at, &value, sizeof value);
}
template <class T>
T get(std::string_view in, std::size_t at) {
  T value;
  std::memcpy(&value, in.data() + at, sizeof value);
  return value;
}

}  // namespace

std::string encode_frame(const Frame& f) {
  const std::size_t n = f.speeds.size();
  if (f.positions.size() != 3 * n)
    throw std::invalid_argument("encode_frame: 3N positions and N speeds");
  std::string out(kFrameHeaderBytes + 16 * n, '\0');
  put<std::uint32_t>(out, 0, kFrameMagic);
  put<std::uint32_t>(out, 4, f.topology);
  put<double>(out, 8, f.time);
  put<std::uint64_t>(out, 16, f.step);
  put<std::uint32_t>(out, 24, static_cast<std::uint32_t>(n));
  put<std::uint32_t>(out, 28, f.playing ? 1u : 0u);
  put<double>(out, 32, f.kinetic);
  put<double>(out, 40, f.potential);
  if (n > 0) {
    std::memcpy(out.data() + kFrameHeaderBytes, f.positions.data(), 12 * n);
    std::memcpy(out.data() + kFrameHeaderBytes + 12 * n, f.speeds.data(), 4 * n);
  }
  return out;
}

Frame decode_frame(std::string_view in) {
  if (in.size() < kFrameHeaderBytes) {
    throw ProtocolError(fmt::format("frame of {} bytes is shorter than its {}-byte header",
                                    in.size(), kFrameHeaderBytes));
  }
  if (get<std::uint32_t>(in, 0) != kFrameMagic)
    throw ProtocolError("frame does not start with PDYF");
  Frame f;
  f.topology = get<std::uint32_t>(in, 4);
  f.time = get<double>(in, 8);
  f.step = get<std::uint64_t>(in, 16);
  const std::size_t n = get<std::uint32_t>(in, 24);
  f.playing = (get<std::uint32_t>(in, 28) & 1u) != 0;
  f.kinetic = get<double>(in, 32);
  f.potential = get<double>(in, 40);
  if (in.size() != kFrameHeaderBytes + 16 * n) {
    throw ProtocolError(fmt::format("frame of {} bytes for {} particles (expected {})", in.size(),
                                    n, kFrameHeaderBytes + 16 * n));
  }
  f.positions.resize(3 * n);
  f.speeds.resize(n);
  std::memcpy(f.positions.data(), in.data() + kFrameHeaderBytes, 12 * n);
  std::memcpy(f.speeds.data(), in.data() + kFrameHeaderBytes + 12 * n, 4 * n);
  return f;
}

// ---------------------------------------------------------------------------
// Commands

namespace {

using Op = Command::Op;

struct OpInfo {
  const char* name;
  Op op;
};
constexpr OpInfo kOps[] = {
    {"play", Op::Play},     {"pause", Op::Pause},   {"step", Op::Step},       {"reset", Op::Reset},
    {"reload", Op::Reload}, {"speed", Op::Speed},   {"solver", Op::Solver},   {"dt", Op::Dt},
    {"drag", Op::Drag},     {"move", Op::Move},     {"release", Op::Release}, {"nail", Op::Nail},
    {"create", Op::Create}, {"attach", Op::Attach},
};

std::string op_list() {
  std::string s;
  for (const auto& o : kOps) s += (s.empty() ? "" : ", ") + std::string(o.name);
  return s;
}

// Field readers: each names the op and the field in its message.
class Fields {
 public:
  Fields(const json& j, std::string op) : j_(j), op_(std::move(op)) {}

  const json* find(const char* key) const {
    const auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  [[noreturn]] void fail(const char* key, const std::string& what) const {
    throw ProtocolError(fmt::format("{}: field '{}' {}", op_, key, what));
  }
  double number(const char* key, bool positive) const {
    const json* v = find(key);
    if (!v) fail(key, "is missing (expected a number)");
    if (!v->is_number()) fail(key, fmt::format("is {} (expected a number)", v->type_name()));
    const double x = v->get<double>();
    if (!std::isfinite(x)) fail(key, "is not finite (expected a finite number)");
    if (positive && !(x > 0)) fail(key, fmt::format("is {} (expected a number > 0)", x));
    return x;
  }
  std::optional<double> optional_nonnegative(const char* key) const {
    if (!find(key)) return std::nullopt;
    const double x = number(key, false);
    if (x < 0) fail(key, fmt::format("is {} (expected a number >= 0)", x));
    return x;
  }
  Index index(const char* key) const {
    const json* v = find(key);
    if (!v) fail(key, "is missing (expected a particle index, an integer >= 0)");
    if (!v->is_number_integer() || (v->is_number_integer() && v->get<std::int64_t>() < 0)) {
      fail(key, fmt::format("is {} (expected a particle index, an integer >= 0)", v->dump()));
    }
    return static_cast<Index>(v->get<std::int64_t>());
  }
  Vec3 point(const char* key) const {
    const json* v = find(key);
    const char* expected = "(expected [x, y, z], three finite numbers in m)";
    if (!v) fail(key, fmt::format("is missing {}", expected));
    if (!v->is_array() || v->size() != 3)
      fail(key, fmt::format("is {} {}", short_dump(*v), expected));
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      const json& c = (*v)[static_cast<std::size_t>(k)];
      if (!c.is_number() || !std::isfinite(c.get<double>())) {
        fail(key, fmt::format("is {} {}", short_dump(*v), expected));
      }
      p(k) = c.get<double>();
    }
    return p;
  }
  std::string string(const char* key) const {
    const json* v = find(key);
    if (!v || !v->is_string()) fail(key, "is missing or not a string (expected a solver name)");
    return v->get<std::string>();
  }

 private:
  static std::string short_dump(const json& v) {
    std::string s = v.dump();
    return s.size() > 60 ? s.substr(0, 57) + "..." : s;
  }
  const json& j_;
  std::string op_;
};

}  // namespace

Command parse_command(std::string_view text) {
  if (text.size() > kMaxCommandBytes) {
    throw ProtocolError(fmt::format("message of {} bytes is too long (expected at most {} bytes)",
                                    text.size(), kMaxCommandBytes));
  }
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw ProtocolError(
        fmt::format("message is not JSON: {} (expected a JSON object with an 'op')", e.what()));
  }
  if (!j.is_object()) {
    throw ProtocolError(
        fmt::format("message is a JSON {} (expected a JSON object with an 'op')", j.type_name()));
  }
  const auto op_it = j.find("op");
  if (op_it == j.end() || !op_it->is_string()) {
    throw ProtocolError("message has no 'op' string (expected one of: " + op_list() + ")");
  }
  Command c;
  c.op_name = op_it->get<std::string>();
  bool known = false;
  for (const auto& o : kOps) {
    if (c.op_name == o.name) {
      c.op = o.op;
      known = true;
    }
  }
  if (!known) {
    std::string shown = c.op_name.size() > 40 ? c.op_name.substr(0, 37) + "..." : c.op_name;
    throw ProtocolError(fmt::format("unknown op '{}' (expected one of: {})", shown, op_list()));
  }
  const Fields f(j, c.op_name);
  switch (c.op) {
    case Op::Speed:
    case Op::Dt:
      c.value = f.number("value", true);
      break;
    case Op::Solver:
      c.name = f.string("name");
      break;
    case Op::Drag:
      c.id = f.index("id");
      c.point = f.point("point");
      c.ks = f.optional_nonnegative("ks");
      c.kd = f.optional_nonnegative("kd");
      break;
    case Op::Move:
      c.point = f.point("point");
      break;
    case Op::Nail:
      c.id = f.index("id");
      break;
    case Op::Create:
      c.point = f.point("point");
      c.mass = f.number("mass", true);
      break;
    case Op::Attach:
      c.a = f.index("a");
      c.b = f.index("b");
      c.ks = f.optional_nonnegative("ks");
      c.kd = f.optional_nonnegative("kd");
      break;
    default:
      break;
  }
  return c;
}

std::string error_message(std::string_view op, std::string_view message) {
  json j{{"type", "error"}, {"message", std::string(message)}};
  j["op"] = op.empty() ? json(nullptr) : json(std::string(op));
  // A message echoing a client's bytes may hold invalid UTF-8: replace it
  // rather than throw while reporting an error.
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string ack_message(std::string_view op, std::optional<Index> id) {
  json j{{"type", "ack"}, {"op", std::string(op)}};
  if (id) j["id"] = *id;
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace pdyn::viewer
