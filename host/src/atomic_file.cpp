// AtomicFile: an output written under a temporary name and renamed when
// complete, so that a file under its final name is never partial; resumable
// from a checkpoint's mark (the prefix is copied and its CRC checked).
#include <fmt/format.h>
#include <unistd.h>

#include <cstring>

#include "pdyn/host/runner.hpp"

namespace pdyn {

namespace fs = std::filesystem;

namespace {

// Copies the first mark.bytes bytes of `source` into `dest`, returning false
// (and copying nothing usable) if the file is shorter or its CRC differs. On
// success `crc` holds the running CRC of the copied bytes, ready to go on.
bool copy_prefix(const fs::path& source, const OutputMark& mark, std::FILE* dest,
                 boost::crc_32_type& crc) {
  std::FILE* in = std::fopen(source.c_str(), "rb");
  if (!in) return false;
  crc.reset();
  std::vector<char> buf(1 << 16);
  std::uint64_t left = mark.bytes;
  bool ok = true;
  while (left > 0 && ok) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(left, buf.size()));
    const std::size_t got = std::fread(buf.data(), 1, want, in);
    ok = got == want;
    crc.process_bytes(buf.data(), got);
    ok = ok && std::fwrite(buf.data(), 1, got, dest) == got;
    left -= got;
  }
  std::fclose(in);
  return ok && crc.checksum() == mark.crc;
}

}  // namespace

AtomicFile::AtomicFile(fs::path path, const OutputMark* resume) : path_(std::move(path)) {
  std::error_code ec;
  if (path_.has_parent_path()) fs::create_directories(path_.parent_path(), ec);
  // The name written to until commit(); the fatal-signal report
  // (crash_report.hpp) gets it from temp_path().
  temp_ = path_;
  temp_ += fmt::format(".tmp-{}", ::getpid());
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) {
    throw Error(
        fmt::format("{}: cannot create output file ({})", path_.string(), std::strerror(errno)));
  }
  if (!resume) return;
  try {
    resume_from(*resume);
  } catch (...) {
    // The destructor does not run for an object whose constructor threw:
    // remove the temporary file here, so a refused resume leaves nothing.
    std::fclose(file_);
    file_ = nullptr;
    std::error_code ignored;
    fs::remove(temp_, ignored);
    throw;
  }
}

void AtomicFile::resume_from(const OutputMark& mark) {
  std::error_code ec;
  // The final file of an interrupted run, or the temporary one of a run
  // that was killed outright.
  std::vector<fs::path> candidates{path_};
  const std::string prefix = path_.filename().string() + ".tmp-";
  const fs::path dir = path_.has_parent_path() ? path_.parent_path() : fs::path(".");
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().filename() != temp_.filename()) {
      candidates.push_back(e.path());
    }
  }
  for (const auto& c : candidates) {
    if (std::fseek(file_, 0, SEEK_SET) != 0) break;
    if (copy_prefix(c, mark, file_, crc_)) {
      bytes_ = mark.bytes;
      return;
    }
  }
  throw CheckpointError(fmt::format(
      "{}: cannot resume this output: no file holds the {} bytes the checkpoint recorded "
      "(expected the file written by the interrupted run)",
      path_.string(), mark.bytes));
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::write(const char* data, std::size_t n) {
  if (std::fwrite(data, 1, n, file_) != n) {
    throw Error(
        fmt::format("{}: cannot write output file ({})", path_.string(), std::strerror(errno)));
  }
  crc_.process_bytes(data, n);
  bytes_ += n;
}

OutputMark AtomicFile::mark() {
  std::fflush(file_);
  return {path_.string(), bytes_, crc_.checksum()};
}

void AtomicFile::commit() {
  const bool ok = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  std::error_code ec;
  if (ok && closed) fs::rename(temp_, path_, ec);
  if (!ok || !closed || ec) {
    fs::remove(temp_, ec);
    throw Error(fmt::format("{}: cannot write output file", path_.string()));
  }
}

}  // namespace pdyn
