// pdyn::OutputFile (pdyn/output_file.hpp): whole or absent under its final
// name, continued exactly after a checkpoint, and, after a write fails (a
// full disk: here a file-size limit, which fails write(2) with EFBIG), kept
// up to its last complete frame by mark() and commit() alone.
#include "pdyn/output_file.hpp"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <iterator>
#include <string>

#include "support/test_support.hpp"

namespace {

namespace fs = std::filesystem;
using pdyn::FileMark;
using pdyn::OutputFile;
using pdyn::test::temp_dir;

using pdyn::test::read_bytes;

// Frame k: 1000 bytes of the digit k % 10 and a newline.
std::string frame(int k) { return std::string(1000, static_cast<char>('0' + k % 10)) + "\n"; }

TEST(OutputFile, AppearsWholeAtCommitAndResumesAtItsMark) {
  const fs::path dir = temp_dir("output-file-commit");
  const fs::path path = dir / "out/frames.txt";
  FileMark at2;
  {
    OutputFile f(path);
    for (int k = 0; k < 4; ++k) {
      f.begin_frame();
      f.write(frame(k));
      f.flush();
      if (k == 1) at2 = f.mark();
      EXPECT_FALSE(fs::exists(path));
      EXPECT_TRUE(fs::exists(f.temp_path()));
    }
    EXPECT_FALSE(f.failed());
    f.commit();
  }
  std::string four;
  for (int k = 0; k < 4; ++k) four += frame(k);
  EXPECT_EQ(read_bytes(path), four);
  EXPECT_EQ(at2.bytes, 2002u);
  EXPECT_EQ(at2.crc, pdyn::crc32(four.data(), 2002));
  // Resumed at frame 2: the first two frames are taken from the file,
  // checked by their CRC, and the rest is written again.
  {
    OutputFile f(path, &at2);
    for (int k = 2; k < 4; ++k) f.write(frame(k));
    f.commit();
  }
  EXPECT_EQ(read_bytes(path), four);
  FileMark wrong = at2;
  wrong.crc ^= 1;
  EXPECT_THROW(OutputFile(path, &wrong), pdyn::ResumeError);
  // Destroyed without commit: nothing is left, not even the temporary file.
  fs::path temp;
  {
    OutputFile f(dir / "never.txt");
    f.write("x");
    temp = f.temp_path();
  }
  EXPECT_FALSE(fs::exists(dir / "never.txt"));
  EXPECT_FALSE(fs::exists(temp));
}

// The child process writes 1001-byte frames under a 5500-byte file limit:
// frames 0-4 fit (5005 bytes), frame 5 does not. Exit status: 0 if every
// check held, else the number of the check that failed.
int write_until_full(const fs::path& path) {
  std::signal(SIGXFSZ, SIG_IGN);  // a failed write(2), not a killed process
  const rlimit limit{5500, 5500};
  if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) return 10;
  OutputFile f(path);
  int k = 0;
  try {
    for (; k < 100; ++k) {
      f.begin_frame();
      f.write(frame(k));
      f.flush();
    }
    return 11;  // never full
  } catch (const pdyn::Error& e) {
    if (std::string(e.what()).find("cannot write output file") == std::string::npos) return 12;
  }
  if (k != 5) return 13;
  if (!f.failed()) return 14;
  const FileMark m = f.mark();  // no throw: the last complete frame
  if (m.bytes != 5005) return 15;
  if (f.mark().bytes != 5005) return 16;  // the same on every call
  try {
    f.write("more");
    return 17;  // a failed file takes nothing more
  } catch (const pdyn::Error&) {
  }
  f.commit();  // cut back to frame 4's end, then renamed
  return 0;
}

TEST(OutputFile, AFullDiskKeepsTheCompleteFrames) {
  const fs::path dir = temp_dir("output-file-full");
  const fs::path path = dir / "frames.txt";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) ::_exit(write_until_full(path));
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "child killed by signal " << WTERMSIG(status);
  ASSERT_EQ(WEXITSTATUS(status), 0) << "check " << WEXITSTATUS(status) << " failed";
  std::string five;
  for (int k = 0; k < 5; ++k) five += frame(k);
  EXPECT_EQ(read_bytes(path), five);
  EXPECT_TRUE(pdyn::leftover_temporaries(path).empty());
}

}  // namespace
