// OutputFile (pdyn/output_file.hpp): outputs under a temporary name until
// complete, continued from a checkpoint's mark after a CRC check. The host's
// checkpoints recorded the same (bytes, CRC-32) pair before writers were
// plugins, so marks of older checkpoints still continue today's files.
#include "pdyn/output_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

namespace pdyn {

namespace fs = std::filesystem;

namespace {

constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
constexpr auto kCrcTable = make_crc_table();

// Copies the first mark.bytes bytes of `source` into `dest`; false if the
// file is shorter or its CRC differs. On success `crc` is the CRC so far.
bool copy_prefix(const fs::path& source, const FileMark& mark, std::FILE* dest,
                 std::uint32_t& crc) {
  std::FILE* in = std::fopen(source.c_str(), "rb");
  if (!in) return false;
  crc = 0;
  std::vector<char> buf(1 << 16);
  std::uint64_t left = mark.bytes;
  bool ok = true;
  while (left > 0 && ok) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(left, buf.size()));
    const std::size_t got = std::fread(buf.data(), 1, want, in);
    ok = got == want;
    crc = crc32(buf.data(), got, crc);
    ok = ok && std::fwrite(buf.data(), 1, got, dest) == got;
    left -= got;
  }
  std::fclose(in);
  return ok && crc == mark.crc;
}

std::string write_failure(const fs::path& path, int err) {
  return fmt::format("{}: cannot write output file ({})", path.string(), std::strerror(err));
}

}  // namespace

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = kCrcTable[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::vector<std::uint8_t> FileMark::encode() const {
  std::vector<std::uint8_t> out(12);
  for (int k = 0; k < 8; ++k) out[k] = static_cast<std::uint8_t>(bytes >> (8 * k));
  for (int k = 0; k < 4; ++k) out[8 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
  return out;
}

FileMark FileMark::decode(std::span<const std::uint8_t> data) {
  if (data.size() != 12) {
    throw Error(
        fmt::format("an output mark of {} bytes (expected 12: length and CRC-32)", data.size()));
  }
  FileMark m;
  for (int k = 0; k < 8; ++k) m.bytes |= static_cast<std::uint64_t>(data[k]) << (8 * k);
  for (int k = 0; k < 4; ++k) m.crc |= static_cast<std::uint32_t>(data[8 + k]) << (8 * k);
  return m;
}

fs::path temporary_name(const fs::path& path) {
  fs::path temp = path;
  temp += fmt::format(".tmp-{}", ::getpid());
  return temp;
}

std::vector<fs::path> leftover_temporaries(const fs::path& path) {
  std::vector<fs::path> found;
  std::error_code ec;
  const std::string prefix = path.filename().string() + ".tmp-";
  const fs::path mine = temporary_name(path).filename();
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().filename() != mine) found.push_back(e.path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

OutputFile::OutputFile(fs::path path, const FileMark* resume)
    : path_(std::move(path)), temp_(temporary_name(path_)), boundaries_(1) {
  std::error_code ec;
  if (path_.has_parent_path()) fs::create_directories(path_.parent_path(), ec);
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) {
    throw Error(
        fmt::format("{}: cannot create output file ({})", path_.string(), std::strerror(errno)));
  }
  if (!resume) return;
  try {
    resume_from(*resume);
  } catch (...) {
    // No destructor runs for an object whose constructor threw: a refused
    // resume leaves nothing behind.
    std::fclose(file_);
    file_ = nullptr;
    fs::remove(temp_, ec);
    throw;
  }
}

void OutputFile::resume_from(const FileMark& mark) {
  // The final file of an interrupted run, or the temporary one of a run
  // that was killed outright.
  std::vector<fs::path> candidates{path_};
  for (auto& p : leftover_temporaries(path_)) candidates.push_back(std::move(p));
  for (const auto& c : candidates) {
    if (std::fseek(file_, 0, SEEK_SET) != 0) break;
    if (copy_prefix(c, mark, file_, crc_)) {
      bytes_ = mark.bytes;
      boundaries_.assign(1, written());
      resumed_ = true;
      return;
    }
  }
  throw ResumeError(fmt::format(
      "{}: cannot resume this output: no file holds the {} bytes the checkpoint recorded "
      "(expected the file written by the interrupted run)",
      path_.string(), mark.bytes));
}

OutputFile::~OutputFile() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

// A failed write or flush fails the file: from then on mark() and commit()
// stop at its last complete frame (whole_, found now).
void OutputFile::write(const void* data, std::size_t n) {
  if (whole_) throw Error(write_failure(path_, EIO));
  if (std::fwrite(data, 1, n, file_) != n) fail(errno);
  crc_ = crc32(data, n, crc_);
  bytes_ += n;
}

FileMark OutputFile::mark() {
  if (whole_) return *whole_;
  if (std::fflush(file_) != 0) fail(errno);
  boundaries_.assign(1, written());
  return {bytes_, crc_};
}

void OutputFile::flush() {
  if (whole_) throw Error(write_failure(path_, EIO));
  if (std::fflush(file_) != 0) fail(errno);
  // Start the disk writing what was flushed, without waiting for it: the
  // fsync at commit() then has only the last frames left, instead of the
  // whole file at the end of the run. A hint; its failure is not an error.
  ::sync_file_range(::fileno(file_), 0, 0, SYNC_FILE_RANGE_WRITE);
}

void OutputFile::fail(int err) {
  last_whole_frame();
  throw Error(write_failure(path_, err));
}

FileMark OutputFile::last_whole_frame() {
  if (whole_) return *whole_;
  if (file_) std::fflush(file_);  // as much as still fits
  std::error_code ec;
  const auto size = fs::file_size(temp_, ec);
  whole_ = FileMark{};
  for (const auto& b : boundaries_) {
    if (!ec && b.bytes <= size) whole_ = b;
  }
  // Every frame that began was followed by a successful write of it: the
  // file ends at the current position.
  if (!ec && size >= bytes_) whole_ = written();
  return *whole_;
}

void OutputFile::commit() {
  if (whole_) return commit_at(*whole_);
  const bool ok = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const int err = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  std::error_code ec;
  if (ok && closed) fs::rename(temp_, path_, ec);
  if (ok && closed && !ec && resumed_) remove_leftovers(path_);
  if (!ok || !closed || ec) {
    std::error_code ignored;
    fs::remove(temp_, ignored);
    throw Error(write_failure(path_, ok ? (ec ? ec.value() : errno) : err));
  }
}

void OutputFile::commit_at(const FileMark& mark, std::string_view tail) {
  std::fclose(file_);  // may fail to flush the rest: it is cut off below anyway
  file_ = nullptr;
  bytes_ = mark.bytes;
  crc_ = mark.crc;
  bool ok = ::truncate(temp_.c_str(), static_cast<off_t>(mark.bytes)) == 0;
  int err = errno;
  if (ok) {
    const int fd = ::open(temp_.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
    ok = fd >= 0 &&
         (tail.empty() ||
          ::write(fd, tail.data(), tail.size()) == static_cast<ssize_t>(tail.size())) &&
         ::fsync(fd) == 0;
    err = errno;
    if (fd >= 0) ::close(fd);
  }
  std::error_code ec;
  if (ok) fs::rename(temp_, path_, ec);
  if (ok && !ec && resumed_) remove_leftovers(path_);
  if (!ok || ec) {
    std::error_code ignored;
    fs::remove(temp_, ignored);
    throw Error(write_failure(path_, ok ? ec.value() : err));
  }
}

void remove_leftovers(const fs::path& path) {
  std::error_code ec;
  for (const auto& p : leftover_temporaries(path)) fs::remove(p, ec);
}

void write_file_atomically(const fs::path& path, std::span<const char> data) {
  const fs::path temp = temporary_name(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  int err = ok ? 0 : errno;
  std::size_t done = 0;
  while (ok && done < data.size()) {
    const ssize_t k = ::write(fd, data.data() + done, data.size() - done);
    if (k < 0 && errno == EINTR) continue;
    ok = k > 0;
    if (ok)
      done += static_cast<std::size_t>(k);
    else
      err = k == 0 ? ENOSPC : errno;
  }
  if (ok && ::fsync(fd) != 0) {
    ok = false;
    err = errno;
  }
  if (fd >= 0 && ::close(fd) != 0 && ok) {
    ok = false;
    err = errno;
  }
  std::error_code ec;
  if (ok) fs::rename(temp, path, ec);
  if (!ok || ec) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw Error(write_failure(path, ok ? ec.value() : err));
  }
}

}  // namespace pdyn
