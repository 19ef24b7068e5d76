// The checkpoint file format, version 7 (native byte order, x86-64):
//
//   "PDYNCKPT"                8 bytes magic
//   u32 format version        Checkpoint::kFormatVersion
//   u64 payload length        bytes that follow, before the CRC
//   payload                   fields below, in this order
//   u32 CRC-32 of payload     (ISO-HDLC, as zlib; pdyn::crc32)
//
// Payload: string scene_file, string scene_text, i64 step, f64 time,
// i64 next_frame, u8 has_dense, u64 N, f64[6N] state, f64[N] mass, u8[N] fixed,
// i32[3N] images (x, y, z per particle), u64 count, count x (string label,
// bytes state), u64 writers, writers x (string path, bytes mark, i8
// wrote_state, u64 pending, pending x bytes frame), u8 has_reused, f64[3N]
// reused accelerations if has_reused. A string or byte block is a u64
// length and its bytes.
//
// Version 7 appends u8 has_box, then f64[3] min, f64[3] max and u8[3]
// periodic of the box if has_box: a barostat changes the box during a run.
// Version 6 is version 7 without the box (the scene's box is kept).
// Version 5 is version 6 without the reused accelerations (a resumed run
// then evaluates the forces afresh at its first step).
// Version 4 is version 5 without the pending frames (read as none).
// Version 3 ended with 2 x (string path, u64 bytes, u32 crc) instead of the
// writers: the frames CSV and the energy CSV, which are today's csv and
// energy writers, whose mark is that (bytes, crc) pair (pdyn::FileMark).
// Version 2 is version 3 without `images`; it is still read, with every
// image count 0 (no scene had a periodic box then).
//
// The length and CRC are checked before any field is parsed, and every read
// is bounds-checked, so a truncated or corrupted file is refused whole.
#include "pdyn/host/checkpoint.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <pdyn/output_file.hpp>
#include <sstream>

namespace pdyn {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'P', 'D', 'Y', 'N', 'C', 'K', 'P', 'T'};

class ByteWriter {
 public:
  template <class T>
  void pod(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    buf_.append(p, sizeof(T));
  }
  void bytes(const void* data, std::size_t n) {
    pod<std::uint64_t>(n);
    buf_.append(static_cast<const char*>(data), n);
  }
  void string(const std::string& s) { bytes(s.data(), s.size()); }
  const std::string& data() const { return buf_; }

 private:
  std::string buf_;
};

class ByteReader {
 public:
  ByteReader(const std::string& data, std::string file) : data_(data), file_(std::move(file)) {}
  template <class T>
  T pod() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string bytes() {
    const auto n = pod<std::uint64_t>();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  void doubles(double* out, std::uint64_t n) {
    if (n > data_.size() / sizeof(double)) fail("a vector is longer than the file");
    need(n * sizeof(double));
    std::memcpy(out, data_.data() + pos_, n * sizeof(double));
    pos_ += n * sizeof(double);
  }
  bool done() const { return pos_ == data_.size(); }
  [[noreturn]] void fail(const std::string& what) const {
    throw CheckpointError(
        fmt::format("{}: corrupt checkpoint: {} (expected a file written by "
                    "pdyn run)",
                    file_, what));
  }

 private:
  void need(std::uint64_t n) const {
    if (n > data_.size() - pos_) fail("a field runs past the end of the payload");
  }
  const std::string& data_;
  std::string file_;
  std::size_t pos_ = 0;
};

// The writers' CRC-32 (pdyn/output_file.hpp), the same checksum as
// boost::crc_32_type and zlib's, so a checkpoint and its writers' marks use
// one implementation.
std::uint32_t crc32(const std::string& s) { return pdyn::crc32(s.data(), s.size()); }

}  // namespace

const WriterMark* Checkpoint::output(const std::string& path) const {
  for (const auto& m : outputs) {
    if (m.path == path) return &m;
  }
  return nullptr;
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

void write_checkpoint(const fs::path& path, const Checkpoint& c) {
  ByteWriter w;
  w.string(c.scene_file);
  w.string(c.scene_text);
  w.pod(c.step);
  w.pod(c.time);
  w.pod(c.next_frame);
  w.pod<std::uint8_t>(c.has_dense ? 1 : 0);
  const std::uint64_t n = static_cast<std::uint64_t>(c.mass.size());
  w.pod(n);
  std::string payload = w.data();
  payload.append(reinterpret_cast<const char*>(c.state.data()), 6 * n * sizeof(double));
  payload.append(reinterpret_cast<const char*>(c.mass.data()), n * sizeof(double));
  payload.append(reinterpret_cast<const char*>(c.fixed.data()), n);
  if (c.images.size() == n) {
    payload.append(reinterpret_cast<const char*>(c.images.data()), 3 * n * sizeof(std::int32_t));
  } else {  // a checkpoint built without them: none wrapped
    payload.append(3 * n * sizeof(std::int32_t), '\0');
  }
  ByteWriter tail;
  tail.pod<std::uint64_t>(c.plugin_states.size());
  for (const auto& [label, bytes] : c.plugin_states) {
    tail.string(label);
    tail.bytes(bytes.data(), bytes.size());
  }
  tail.pod<std::uint64_t>(c.outputs.size());
  for (const auto& m : c.outputs) {
    tail.string(m.path);
    tail.bytes(m.mark.data(), m.mark.size());
    tail.pod(m.wrote_state);
    tail.pod<std::uint64_t>(m.pending.size());
    for (const auto& frame : m.pending) tail.bytes(frame.data(), frame.size());
  }
  const bool reused = c.reused.cols() == static_cast<Index>(n) && n > 0;
  tail.pod<std::uint8_t>(reused ? 1 : 0);
  payload += tail.data();
  if (reused) {
    payload.append(reinterpret_cast<const char*>(c.reused.data()), 3 * n * sizeof(double));
  }
  ByteWriter box;
  box.pod<std::uint8_t>(c.box ? 1 : 0);
  if (c.box) {
    for (int k = 0; k < 3; ++k) box.pod(c.box->min[k]);
    for (int k = 0; k < 3; ++k) box.pod(c.box->max[k]);
    for (int k = 0; k < 3; ++k) box.pod<std::uint8_t>(c.box->periodic[k] ? 1 : 0);
  }
  payload += box.data();

  ByteWriter file;
  std::string out(kMagic, sizeof(kMagic));
  file.pod(Checkpoint::kFormatVersion);
  file.pod<std::uint64_t>(payload.size());
  out += file.data();
  out += payload;
  const std::uint32_t crc = crc32(payload);
  out.append(reinterpret_cast<const char*>(&crc), sizeof(crc));

  std::error_code ec;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  fs::path temp = path;
  temp += fmt::format(".tmp-{}", ::getpid());
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  std::size_t done = 0;
  while (ok && done < out.size()) {
    const ssize_t k = ::write(fd, out.data() + done, out.size() - done);
    if (k < 0 && errno == EINTR) continue;
    ok = k > 0;
    if (ok) done += static_cast<std::size_t>(k);
  }
  ok = ok && ::fsync(fd) == 0;
  if (fd >= 0) ok = (::close(fd) == 0) && ok;
  if (ok) fs::rename(temp, path, ec);
  if (!ok || ec) {
    fs::remove(temp, ec);
    throw Error(
        fmt::format("{}: cannot write checkpoint ({})", path.string(), std::strerror(errno)));
  }
}

namespace {

// The whole file, or a CheckpointError saying why it cannot be read.
std::string checkpoint_bytes(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  std::string why;
  if (status.type() == fs::file_type::not_found) {
    why = "no such file";
  } else if (ec) {
    why = ec.message();
  } else if (fs::is_directory(status)) {
    why = "it is a folder";
  }
  std::ifstream in;
  if (why.empty()) {
    in.open(path, std::ios::binary);
    if (!in) why = std::strerror(errno);
  }
  if (!why.empty()) {
    throw CheckpointError(
        fmt::format("{}: cannot read checkpoint: {} (expected a file written "
                    "by pdyn run)",
                    path.string(), why));
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The payload after the header's checks (magic, format version, length)
// and the CRC's; `version` is the file's format version.
std::string checked_payload(const std::string& data, const std::string& file,
                            std::uint32_t& version) {
  constexpr std::size_t kHeader = sizeof(kMagic) + sizeof(std::uint32_t) + sizeof(std::uint64_t);
  if (data.empty()) {
    throw CheckpointError(
        fmt::format("{}: checkpoint is empty (expected a file written by "
                    "pdyn run)",
                    file));
  }
  if (std::memcmp(data.data(), kMagic, std::min(data.size(), sizeof(kMagic))) != 0) {
    throw CheckpointError(
        fmt::format("{}: not a pdyn checkpoint (expected a file written by "
                    "pdyn run)",
                    file));
  }
  if (data.size() < kHeader) {
    throw CheckpointError(
        fmt::format("{}: checkpoint is truncated ({} bytes, shorter than its "
                    "{}-byte header)",
                    file, data.size(), kHeader));
  }
  std::uint64_t length = 0;
  std::memcpy(&version, data.data() + sizeof(kMagic), sizeof(version));
  std::memcpy(&length, data.data() + sizeof(kMagic) + sizeof(version), sizeof(length));
  if (version < Checkpoint::kOldestReadableVersion || version > Checkpoint::kFormatVersion) {
    const std::uint32_t oldest = Checkpoint::kOldestReadableVersion,
                        newest_old = Checkpoint::kFormatVersion - 1;
    const std::string older = oldest == newest_old
                                  ? fmt::format("version {}", oldest)
                                  : fmt::format("versions {} to {}", oldest, newest_old);
    throw CheckpointError(
        fmt::format("{}: checkpoint format version {} is not supported "
                    "(expected version {}, or {} from an earlier pdyn)",
                    file, version, Checkpoint::kFormatVersion, older));
  }
  // As unsigned sums, so that a corrupted length cannot wrap around.
  const std::uint64_t have = data.size() - kHeader;
  if (have < sizeof(std::uint32_t) || length > have - sizeof(std::uint32_t)) {
    throw CheckpointError(
        fmt::format("{}: checkpoint is truncated ({} bytes; its header "
                    "announces a {}-byte payload)",
                    file, data.size(), length));
  }
  if (length < have - sizeof(std::uint32_t)) {
    throw CheckpointError(fmt::format(
        "{}: checkpoint has {} trailing bytes after its checksum "
        "(expected {} bytes)",
        file, have - sizeof(std::uint32_t) - length, kHeader + length + sizeof(std::uint32_t)));
  }
  std::string payload = data.substr(kHeader, length);
  std::uint32_t stored = 0;
  std::memcpy(&stored, data.data() + kHeader + length, sizeof(stored));
  if (crc32(payload) != stored) {
    throw CheckpointError(
        fmt::format("{}: checkpoint checksum mismatch: the file is corrupted "
                    "(expected CRC-32 {:08x}, computed {:08x})",
                    file, stored, crc32(payload)));
  }
  return payload;
}

// The plugins' saved states, then the writers' marks (format 4 on; before
// that, the frames and energy files' (bytes, CRC) pairs).
void read_plugins_and_outputs(ByteReader& r, Checkpoint& c, std::uint32_t version,
                              std::size_t payload_size) {
  const auto count = r.pod<std::uint64_t>();
  if (count > payload_size) r.fail("plugin count larger than the file");
  for (std::uint64_t i = 0; i < count; ++i) {
    std::string label = r.bytes();
    std::string bytes = r.bytes();
    c.plugin_states.emplace_back(std::move(label),
                                 std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  }
  if (version >= 4) {
    const auto writers = r.pod<std::uint64_t>();
    if (writers > payload_size) r.fail("writer count larger than the file");
    for (std::uint64_t i = 0; i < writers; ++i) {
      std::string written = r.bytes();
      std::string mark = r.bytes();
      const auto wrote = r.pod<std::int8_t>();
      if (wrote < -1 || wrote > 1) r.fail("a flag is neither -1, 0 nor 1");
      WriterMark w{
          std::move(written), std::vector<std::uint8_t>(mark.begin(), mark.end()), wrote, {}};
      if (version >= 5) {
        const auto pending = r.pod<std::uint64_t>();
        if (pending > payload_size) r.fail("pending frame count larger than the file");
        for (std::uint64_t k = 0; k < pending; ++k) {
          std::string frame = r.bytes();
          w.pending.emplace_back(frame.begin(), frame.end());
        }
      }
      c.outputs.push_back(std::move(w));
    }
  } else {
    for (int k = 0; k < 2; ++k) {  // frames, energy
      std::string written = r.bytes();
      FileMark m;
      m.bytes = r.pod<std::uint64_t>();
      m.crc = r.pod<std::uint32_t>();
      if (!written.empty()) c.outputs.push_back({std::move(written), m.encode(), -1, {}});
    }
  }
}

}  // namespace

Checkpoint read_checkpoint(const fs::path& path) {
  const std::string data = checkpoint_bytes(path);
  const std::string file = path.string();
  std::uint32_t version = 0;
  const std::string payload = checked_payload(data, file, version);
  ByteReader r(payload, file);
  Checkpoint c;
  c.scene_file = r.bytes();
  c.scene_text = r.bytes();
  c.step = r.pod<std::int64_t>();
  c.time = r.pod<double>();
  c.next_frame = r.pod<std::int64_t>();
  const auto has_dense = r.pod<std::uint8_t>();
  if (has_dense > 1) r.fail("a flag is neither 0 nor 1");
  c.has_dense = has_dense == 1;
  const auto n = r.pod<std::uint64_t>();
  if (n > payload.size() / (7 * sizeof(double))) r.fail("particle count larger than the file");
  c.state.resize(static_cast<Index>(6 * n));
  c.mass.resize(static_cast<Index>(n));
  r.doubles(c.state.data(), 6 * n);
  r.doubles(c.mass.data(), n);
  c.fixed.resize(n);
  for (auto& f : c.fixed) f = r.pod<std::uint8_t>();
  c.images.assign(n, {0, 0, 0});
  if (version >= 3) {
    for (auto& image : c.images) {
      for (auto& k : image) k = r.pod<std::int32_t>();
    }
  }
  read_plugins_and_outputs(r, c, version, payload.size());
  if (version >= 6 && r.pod<std::uint8_t>() != 0) {
    c.reused.resize(3, static_cast<Index>(n));
    for (Index k = 0; k < c.reused.size(); ++k) c.reused.data()[k] = r.pod<double>();
  }
  if (version >= 7 && r.pod<std::uint8_t>() != 0) {
    Domain d;
    for (int k = 0; k < 3; ++k) d.min[k] = r.pod<double>();
    for (int k = 0; k < 3; ++k) d.max[k] = r.pod<double>();
    for (int k = 0; k < 3; ++k) d.periodic[k] = r.pod<std::uint8_t>() != 0;
    c.box = d;
  }
  if (!r.done()) r.fail("unexpected bytes after the last field");
  return c;
}

}  // namespace pdyn
