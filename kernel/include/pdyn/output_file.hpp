// pdyn/output_file.hpp — files a writer plugin writes: never partial under
// their final name, and continued exactly by a resumed run.
//
// An OutputFile is written under a temporary name in the same folder
// (`PATH.tmp-PID`) and renamed to PATH by commit(), after fflush and fsync:
// a file under its final name is always complete. One that is destroyed
// without commit() is removed. It keeps a CRC-32 of what was written, so a
// checkpoint can record how far it went (mark()) and a resumed run can check
// that the file it continues is that one (the `resume` constructor).
//
//   pdyn::OutputFile f(path, ctx.resume.empty() ? nullptr : &mark);
//   f.write("t,x\n");           // throws pdyn::Error naming the file on failure
//   f.begin_frame(); f.write(...); f.flush();   // each frame
//   f.mark();                   // for a checkpoint
//   f.commit();                 // now, and only now, PATH exists
//
// After a failed write (a full disk) mark() and commit() stop at the last
// complete frame, so a writer whose only failures are the file's needs no
// bookkeeping of its own.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "pdyn/error.hpp"
#include "pdyn/export.hpp"

namespace pdyn {

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320; the checksum of zip,
/// PNG and boost::crc_32_type). `crc` continues an earlier checksum: start
/// with 0.
PDYN_API std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

/// A resumed output cannot be continued: the file the checkpoint recorded is
/// gone or differs. The host reports it as a checkpoint problem (exit 2).
class PDYN_API ResumeError : public Error {
 public:
  using Error::Error;
};

/// How much of a file belonged to a run at a checkpoint.
struct PDYN_API FileMark {
  std::uint64_t bytes = 0;  ///< length written, bytes
  std::uint32_t crc = 0;    ///< CRC-32 of those bytes

  /// 12 bytes: u64 bytes, u32 crc, little-endian. What a writer whose mark
  /// is one file returns from Writer::mark().
  std::vector<std::uint8_t> encode() const;
  /// Reads encode()'s bytes; throws pdyn::Error if `data` is not 12 bytes.
  static FileMark decode(std::span<const std::uint8_t> data);
};

class PDYN_API OutputFile {
 public:
  /// Starts `path` (creating its folder), or, with `resume`, continues the
  /// file a checkpoint recorded: its first resume->bytes bytes are copied
  /// from the final file or from a temporary file an interrupted run left
  /// (`PATH.tmp-*`), after checking their CRC. Throws pdyn::Error naming the
  /// file if it cannot be created, ResumeError if no file matches the mark.
  explicit OutputFile(std::filesystem::path path, const FileMark* resume = nullptr);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Appends `n` bytes. Throws pdyn::Error "PATH: cannot write output file
  /// (WHY)" on failure (a full disk). A failed write or flush fails the
  /// file (failed()): from then on mark() and commit() keep it up to its
  /// last complete frame, and write() and flush() throw.
  void write(const void* data, std::size_t n);
  void write(std::string_view s) { write(s.data(), s.size()); }
  /// Flushes and returns how far the file has been written; once the file
  /// has failed, last_whole_frame(). Throws pdyn::Error (and fails the
  /// file) if the flush fails.
  FileMark mark();
  /// Hands what is buffered to the system (no fsync). Throws pdyn::Error on
  /// failure: a writer calls it after each frame, so that a full disk is met
  /// at the frame that does not fit.
  void flush();
  /// A write or flush has failed. (Added within ABI 5, layout unchanged:
  /// writers built before it kept a flag of their own and called
  /// last_whole_frame() and commit_at(), which still works.)
  bool failed() const noexcept { return whole_.has_value(); }
  /// What has been written so far (including a resumed prefix), without
  /// flushing: a writer notes it before a frame, so that after a failed
  /// write its mark() can still name the last complete frame.
  FileMark written() const noexcept { return {bytes_, crc_}; }
  /// Flushes, fsyncs, closes and renames to the final name; once the file
  /// has failed, commit_at(last_whole_frame()). Throws pdyn::Error on
  /// failure, after removing the temporary file.
  void commit();
  /// The same, keeping only what `mark` covers (last_whole_frame()): after
  /// a failed write (a full disk), the file up to its last complete frame.
  /// `tail` is appended after the cut (the closing tags of an XML file).
  void commit_at(const FileMark& mark, std::string_view tail = {});

  /// Notes that a frame starts here (call before writing each frame).
  void begin_frame() { boundaries_.push_back(written()); }
  /// After a failed write or mark(): the start of the first frame that is
  /// not wholly on disk, i.e. the end of the last complete one (found from
  /// the file's size on disk and the frame starts noted since the last
  /// successful mark()). The same value on every call.
  FileMark last_whole_frame();
  /// The final name, and the temporary name written to until commit().
  const std::filesystem::path& path() const noexcept { return path_; }
  const std::filesystem::path& temp_path() const noexcept { return temp_; }

 private:
  void resume_from(const FileMark& mark);
  [[noreturn]] void fail(int err);  // finds last_whole_frame(), throws

  std::filesystem::path path_, temp_;
  std::FILE* file_ = nullptr;
  std::uint64_t bytes_ = 0;
  std::uint32_t crc_ = 0;
  bool resumed_ = false;  // continued a file: commit removes what the interrupted run left
  std::vector<FileMark> boundaries_;  // frame starts since the last successful mark()
  std::optional<FileMark> whole_;     // last_whole_frame(), once asked
};

/// `path` with ".tmp-PID" appended: the temporary name OutputFile and
/// write_file_atomically use.
PDYN_API std::filesystem::path temporary_name(const std::filesystem::path& path);

/// Writes `data` to `path` in one go: to temporary_name(path), fsync, then
/// rename. Throws pdyn::Error "PATH: cannot write output file (WHY)", after
/// removing the temporary file.
PDYN_API void write_file_atomically(const std::filesystem::path& path, std::span<const char> data);

/// The files `PATH.tmp-*` that runs which were killed outright left beside
/// `path` (not this process's own).
PDYN_API std::vector<std::filesystem::path> leftover_temporaries(const std::filesystem::path& path);
/// Removes them: a resumed output, once committed, has taken their place.
PDYN_API void remove_leftovers(const std::filesystem::path& path);

}  // namespace pdyn
