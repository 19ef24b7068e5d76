// Bad checkpoints are refused whole: `pdyn run SCENE --resume BAD` exits 2
// with one clear line naming the file and the problem, and leaves every
// file in the run's folder exactly as it was (no output file started,
// truncated or renamed, no temporary left). Covered: truncations at several
// lengths, a flipped byte in the payload and in the checksum, a wrong magic,
// unsupported format versions, trailing garbage, a corrupted length field,
// an empty file, a missing file, a folder, a checkpoint of a different
// scene (refused, naming the differing key; accepted with --force, which
// warns with it), --force with a scene of other particles or plugin
// objects, a checkpoint past the end of a shorter run, and output files
// changed since the checkpoint. Last, a few thousand corrupted payloads with
// a recomputed (valid) checksum, which read_checkpoint and
// restore_checkpoint must refuse with CheckpointError or accept, never crash.
#include <gtest/gtest.h>

#include <boost/crc.hpp>
#include <random>
#include <string_view>

#include "host/resume_support.hpp"
#include "pdyn/host/runner.hpp"
#include "pdyn/output_file.hpp"

namespace pdyn {
namespace {

namespace fs = std::filesystem;
using namespace pdyn::test;

constexpr std::size_t kHeader = 20;  // magic, u32 version, u64 payload length

std::uint32_t crc32(const std::string& s) {
  boost::crc_32_type crc;
  crc.process_bytes(s.data(), s.size());
  return crc.checksum();
}

// A checkpoint with its payload replaced and its header and checksum made
// consistent again.
std::string reseal(const std::string& good, std::string payload) {
  std::string out = good.substr(0, 12);
  const std::uint64_t n = payload.size();
  out.append(reinterpret_cast<const char*>(&n), 8);
  out += payload;
  const std::uint32_t crc = crc32(payload);
  out.append(reinterpret_cast<const char*>(&crc), 4);
  return out;
}

template <class T>
std::string patch(std::string bytes, std::size_t at, T value) {
  std::memcpy(bytes.data() + at, &value, sizeof(T));
  return bytes;
}

class CheckpointCorruption : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = temp_dir("corruption-" +
                    std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    write_file(dir_ / "scene.yaml", sheet_scene("rk4", 5, 0));
    auto r = pdyn_in(dir_, {"run", "scene.yaml", "--steps", "100", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
    good_ = read_bytes(dir_ / "out/run.ckpt");
    ASSERT_GT(good_.size(), 1000u);
  }

  // Resumes from `bytes` (written as bad.ckpt) and expects exit 2, one line
  // on stderr holding each of `expected`, and no file changed.
  void expect_refused(const std::string& bytes, const std::vector<std::string>& expected,
                      const std::vector<std::string>& extra_args = {}) {
    write_bytes(dir_ / "bad.ckpt", bytes);
    expect_refused_path("bad.ckpt", expected, extra_args);
  }

  void expect_refused_path(const std::string& checkpoint, const std::vector<std::string>& expected,
                           const std::vector<std::string>& extra_args = {}) {
    const auto before = snapshot(dir_);
    std::vector<std::string> args = {"run", "scene.yaml", "--steps", "200",
                                     "-q",  "--resume",   checkpoint};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    const auto r = pdyn_in(dir_, args);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(r.out, "");
    const auto lines = lines_of(r.err);
    EXPECT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("pdyn: ", 0), 0u) << r.err;
    for (const auto& e : expected)
      EXPECT_TRUE(contains(r.err, e)) << "no '" << e << "' in: " << r.err;
    expect_unchanged(before);
  }

  void expect_unchanged(const std::map<std::string, std::string>& before) {
    const auto after = snapshot(dir_);
    for (const auto& [name, bytes] : after) {
      if (!before.count(name))
        ADD_FAILURE() << "a refused resume left " << name;
      else if (before.at(name) != bytes)
        ADD_FAILURE() << "a refused resume changed " << name;
    }
    for (const auto& [name, bytes] : before) {
      if (!after.count(name)) ADD_FAILURE() << "a refused resume removed " << name;
    }
  }

  fs::path dir_;
  std::string good_;
};

TEST_F(CheckpointCorruption, TheGoodCheckpointResumes) {
  // The baseline the other cases corrupt: it resumes (into a copy, so that
  // the other cases' output files stay those of the 100-step run).
  const fs::path copy = temp_dir("corruption-good-copy");
  fs::copy(dir_, copy, fs::copy_options::recursive);
  write_bytes(copy / "good.ckpt", good_);
  auto r = pdyn_in(copy, {"run", "scene.yaml", "--steps", "200", "-q", "--resume", "good.ckpt"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(check_frames_file(copy / "out/frames.csv", 36), 41);
}

TEST_F(CheckpointCorruption, Truncated) {
  for (std::size_t n :
       {std::size_t{1}, std::size_t{4}, std::size_t{8}, std::size_t{12}, std::size_t{19}, kHeader,
        kHeader + 1, good_.size() / 2, good_.size() - 5, good_.size() - 4, good_.size() - 1}) {
    SCOPED_TRACE("truncated to " + std::to_string(n) + " of " + std::to_string(good_.size()) +
                 " bytes");
    expect_refused(good_.substr(0, n), {"bad.ckpt", "checkpoint is truncated"});
  }
}

TEST_F(CheckpointCorruption, FlippedByte) {
  for (std::size_t at : {kHeader, kHeader + 9, good_.size() / 2, good_.size() - 5}) {
    SCOPED_TRACE("payload byte " + std::to_string(at) + " flipped");
    std::string bad = good_;
    bad[at] = static_cast<char>(bad[at] ^ 0x10);
    expect_refused(bad, {"bad.ckpt", "checksum mismatch", "corrupted"});
  }
  std::string bad = good_;
  bad.back() = static_cast<char>(bad.back() ^ 0x01);  // in the stored CRC itself
  expect_refused(bad, {"bad.ckpt", "checksum mismatch"});
}

TEST_F(CheckpointCorruption, WrongMagic) {
  std::string bad = good_;
  bad[0] = 'X';
  expect_refused(bad, {"bad.ckpt", "not a pdyn checkpoint"});
  expect_refused("t,id,x,y,z,vx,vy,vz\n0,0,1,2,3,4,5,6\n", {"bad.ckpt", "not a pdyn checkpoint"});
}

TEST_F(CheckpointCorruption, WrongVersion) {
  const std::uint32_t current = Checkpoint::kFormatVersion;
  const std::uint32_t oldest = Checkpoint::kOldestReadableVersion;
  for (std::uint32_t v : {current + 1, oldest - 1, 0u, 0xffffffffu}) {
    SCOPED_TRACE("version " + std::to_string(v));
    expect_refused(
        patch(good_, 8, v),
        {"bad.ckpt", "format version " + std::to_string(v) + " is not supported",
         "expected version " + std::to_string(current) + ", or versions " + std::to_string(oldest) +
             " to " + std::to_string(current - 1) + " from an earlier pdyn)"});
  }
}

// The length of the writer marks at the end of version 5 checkpoint `now`'s
// payload: u64 count, then per writer a path, a mark, i8 wrote_state and
// the pending frames (none here).
std::size_t marks_length(const Checkpoint& now) {
  std::size_t tail = 8;
  for (const auto& m : now.outputs) {
    EXPECT_TRUE(m.pending.empty());
    tail += 8 + m.path.size() + 8 + m.mark.size() + 1 + 8;
  }
  return tail;
}

// The payload of version 5 checkpoint `now` (bytes `payload`) with its
// writer marks in the layout of version 4: without the pending frames.
std::string with_v4_marks(const std::string& payload, const Checkpoint& now) {
  std::string old = payload.substr(0, payload.size() - marks_length(now));
  const std::uint64_t count = now.outputs.size();
  old.append(reinterpret_cast<const char*>(&count), 8);
  for (const auto& m : now.outputs) {
    for (const std::string_view block :
         {std::string_view(m.path),
          std::string_view(reinterpret_cast<const char*>(m.mark.data()), m.mark.size())}) {
      const std::uint64_t n = block.size();
      old.append(reinterpret_cast<const char*>(&n), 8);
      old += block;
    }
    old.push_back(static_cast<char>(m.wrote_state));
  }
  return old;
}

// ... and in the layout of version 3: frames and energy, each a path, u64
// bytes and u32 CRC (the csv and energy writers' marks).
std::string with_v3_marks(const std::string& payload, const Checkpoint& now) {
  std::string old = payload.substr(0, payload.size() - marks_length(now));
  for (std::size_t k = 0; k < 2; ++k) {
    std::string path;
    FileMark mark;
    if (k < now.outputs.size()) {
      path = now.outputs[k].path;
      mark = FileMark::decode(now.outputs[k].mark);
    }
    const std::uint64_t n = path.size();
    old.append(reinterpret_cast<const char*>(&n), 8);
    old += path;
    old.append(reinterpret_cast<const char*>(&mark.bytes), 8);
    old.append(reinterpret_cast<const char*>(&mark.crc), 4);
  }
  return old;
}

// Version 6 had no box (the scene's is kept); version 5 had no reused
// forces (this scene's drag reads velocities, so version 6 holds none
// either: one flag byte); version 4 had no pending
// frames; version 3 held the marks of the frames and energy CSV files,
// which are today's csv and energy writers; version 2, written before the
// simulation box, is version 3 without the image counts. All are still
// read (version 2 as images 0) and resume the run to the same end, byte
// for byte, as the version 7 checkpoint of the same state.
TEST_F(CheckpointCorruption, Versions6To2AreRead) {
  ASSERT_EQ(Checkpoint::kFormatVersion, 7u);
  const Checkpoint now = read_checkpoint(dir_ / "out/run.ckpt");
  ASSERT_EQ(now.outputs.size(), 2u);  // frames.csv, energy.csv
  ASSERT_EQ(now.reused.size(), 0);
  const std::size_t n = static_cast<std::size_t>(now.mass.size());
  const std::string v7_payload = good_.substr(kHeader, good_.size() - kHeader - 4);
  constexpr std::size_t kBox = 1 + 6 * 8 + 3;  // has_box, min, max, periodic
  ASSERT_EQ(v7_payload[v7_payload.size() - kBox], '\1');
  const std::string v6_payload = v7_payload.substr(0, v7_payload.size() - kBox);
  ASSERT_EQ(v6_payload.back(), '\0');  // no reused forces
  const std::string payload = v6_payload.substr(0, v6_payload.size() - 1);
  const std::string v3_payload = with_v3_marks(payload, now);
  // The payload's fields before the images: two strings, i64, f64, i64,
  // u8, u64 N, then 6N + N doubles and N flags.
  const std::size_t images =
      8 + now.scene_file.size() + 8 + now.scene_text.size() + 8 + 8 + 8 + 1 + 8 + 7 * n * 8 + n;
  std::string v2_payload = v3_payload;
  v2_payload.erase(images, 3 * n * sizeof(std::int32_t));
  const std::string v6 = patch(reseal(good_, v6_payload), 8, std::uint32_t{6});
  const std::string v5 = patch(reseal(good_, payload), 8, std::uint32_t{5});
  const std::string v4 = patch(reseal(good_, with_v4_marks(payload, now)), 8, std::uint32_t{4});
  const std::string v3 = patch(reseal(good_, v3_payload), 8, std::uint32_t{3});
  const std::string v2 = patch(reseal(good_, v2_payload), 8, std::uint32_t{2});
  write_bytes(dir_ / "v6.ckpt", v6);
  write_bytes(dir_ / "v5.ckpt", v5);
  write_bytes(dir_ / "v4.ckpt", v4);
  write_bytes(dir_ / "v3.ckpt", v3);
  write_bytes(dir_ / "v2.ckpt", v2);
  for (const char* name : {"v6.ckpt", "v5.ckpt", "v4.ckpt", "v3.ckpt", "v2.ckpt"}) {
    SCOPED_TRACE(name);
    const Checkpoint c = read_checkpoint(dir_ / name);
    EXPECT_TRUE(same_bits(c.state, now.state));
    EXPECT_EQ(c.plugin_states, now.plugin_states);
    ASSERT_EQ(c.outputs.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      EXPECT_EQ(c.outputs[k].path, now.outputs[k].path);
      EXPECT_EQ(c.outputs[k].mark, now.outputs[k].mark);
      EXPECT_EQ(c.outputs[k].pending, now.outputs[k].pending);
    }
  }
  EXPECT_EQ(read_checkpoint(dir_ / "v4.ckpt").outputs[0].wrote_state, now.outputs[0].wrote_state);
  EXPECT_EQ(read_checkpoint(dir_ / "v2.ckpt").images,
            (std::vector<std::array<std::int32_t, 3>>(n, {0, 0, 0})));

  std::map<std::string, std::pair<std::string, std::string>> ends;  // frames, energy
  for (const char* name : {"v2.ckpt", "v3.ckpt", "v4.ckpt", "v5.ckpt", "v6.ckpt", "out/run.ckpt"}) {
    const fs::path copy = temp_dir(std::string("corruption-resume-") + name[1]);
    fs::copy(dir_, copy, fs::copy_options::recursive);
    auto a = pdyn_in(copy, {"run", "scene.yaml", "--steps", "200", "-q", "--resume", name});
    ASSERT_EQ(a.status, 0) << a.err;
    ends[name] = {read_bytes(copy / "out/frames.csv"), read_bytes(copy / "out/energy.csv")};
  }
  EXPECT_EQ(ends["v2.ckpt"], ends["out/run.ckpt"]);
  EXPECT_EQ(ends["v3.ckpt"], ends["out/run.ckpt"]);
  EXPECT_EQ(ends["v4.ckpt"], ends["out/run.ckpt"]);
  EXPECT_EQ(ends["v5.ckpt"], ends["out/run.ckpt"]);
  EXPECT_EQ(ends["v6.ckpt"], ends["out/run.ckpt"]);
  EXPECT_FALSE(read_checkpoint(dir_ / "v6.ckpt").box.has_value());
  EXPECT_TRUE(now.box.has_value());
}

TEST_F(CheckpointCorruption, TrailingGarbage) {
  expect_refused(good_ + "x", {"bad.ckpt", "1 trailing bytes"});
  expect_refused(good_ + good_, {"bad.ckpt", std::to_string(good_.size()) + " trailing bytes"});
}

TEST_F(CheckpointCorruption, CorruptedLengthField) {
  // Lengths that would wrap around or run past the file are refused before
  // anything is allocated or read.
  for (std::uint64_t n : {~std::uint64_t{0}, ~std::uint64_t{0} - 3, std::uint64_t{1} << 62,
                          std::uint64_t{good_.size()}}) {
    SCOPED_TRACE("payload length " + std::to_string(n));
    expect_refused(patch(good_, 12, n), {"bad.ckpt", "truncated"});
  }
  expect_refused(patch(good_, 12, std::uint64_t{7}), {"bad.ckpt", "trailing bytes"});
}

TEST_F(CheckpointCorruption, EmptyMissingOrFolder) {
  expect_refused("", {"bad.ckpt", "checkpoint is empty"});
  expect_refused_path("nowhere.ckpt", {"nowhere.ckpt", "cannot read checkpoint", "no such file"});
  fs::create_directories(dir_ / "folder.ckpt");
  expect_refused_path("folder.ckpt", {"folder.ckpt", "cannot read checkpoint", "folder"});
}

TEST_F(CheckpointCorruption, DifferentScene) {
  write_bytes(dir_ / "good.ckpt", good_);
  // Refused, naming the key that differs.
  expect_refused_path("good.ckpt", {"different scene", "forces[0].g", "--force"},
                      {"--set", "forces[0].g=[0, 0, -1.62]"});
  expect_refused_path("good.ckpt", {"different scene", "simulation.dt"},
                      {"--set", "simulation.dt=0.002"});
  // A changed run length is not a different scene.
  auto longer =
      pdyn_in(dir_, {"run", "scene.yaml", "--duration", "0.15", "-q", "--resume", "good.ckpt"});
  EXPECT_EQ(longer.status, 0) << longer.err;

  // --force resumes anyway and says what differs.
  const fs::path copy = temp_dir("corruption-force");
  write_file(copy / "scene.yaml", sheet_scene("rk4", 5, 0));
  ASSERT_EQ(pdyn_in(copy, {"run", "scene.yaml", "--steps", "100", "-q"}).status, 0);
  auto forced = pdyn_in(copy, {"run", "scene.yaml", "--steps", "200", "-q", "--resume",
                               "out/run.ckpt", "--force", "--set", "forces[0].g=[0, 0, -1.62]"});
  EXPECT_EQ(forced.status, 0) << forced.err;
  const auto lines = lines_of(forced.err);
  ASSERT_EQ(lines.size(), 1u) << forced.err;
  EXPECT_TRUE(contains(lines[0], "warning")) << lines[0];
  EXPECT_TRUE(contains(lines[0], "--force")) << lines[0];
  EXPECT_TRUE(contains(lines[0], "forces[0].g")) << lines[0];
  EXPECT_TRUE(contains(lines[0], "-9.81")) << lines[0];
  EXPECT_TRUE(contains(lines[0], "-1.62")) << lines[0];
  EXPECT_EQ(check_frames_file(copy / "out/frames.csv", 36), 41);
}

TEST_F(CheckpointCorruption, ForceCannotFitOtherParticlesOrPlugins) {
  write_bytes(dir_ / "good.ckpt", good_);
  expect_refused_path("good.ckpt", {"holds 36 particles", "scene has 30"},
                      {"--force", "--set", "particles[0].grid.nx=5"});
  // The solver, gravity, drag, the grid's three spring families and the plane.
  expect_refused_path("good.ckpt", {"state of 7 plugin objects", "scene has 6"},
                      {"--force", "--set", "colliders=[]"});
}

TEST_F(CheckpointCorruption, PastTheEndOfAShorterRun) {
  write_bytes(dir_ / "good.ckpt", good_);
  const auto before = snapshot(dir_);
  auto r = pdyn_in(dir_, {"run", "scene.yaml", "--steps", "50", "-q", "--resume", "good.ckpt"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "at step 100")) << r.err;
  EXPECT_TRUE(contains(r.err, "past the end of this run (step 50")) << r.err;
  expect_unchanged(before);
}

TEST_F(CheckpointCorruption, OutputChangedSinceTheCheckpoint) {
  write_bytes(dir_ / "good.ckpt", good_);
  const std::string frames = read_bytes(dir_ / "out/frames.csv");
  // One digit changed inside the recorded part.
  std::string changed = frames;
  changed[frames.size() / 2] = changed[frames.size() / 2] == '1' ? '2' : '1';
  write_bytes(dir_ / "out/frames.csv", changed);
  expect_refused_path("good.ckpt", {"frames.csv", "cannot resume this output"});
  // Shorter than the recorded part.
  write_bytes(dir_ / "out/frames.csv", frames.substr(0, frames.size() - 10));
  expect_refused_path("good.ckpt", {"frames.csv", "cannot resume this output"});
  // Gone.
  fs::remove(dir_ / "out/frames.csv");
  expect_refused_path("good.ckpt", {"frames.csv", "cannot resume this output"});
}

TEST_F(CheckpointCorruption, ResealedGarbageIsRefusedOrHarmless) {
  // Corrupted payloads with a valid checksum: the format's own bounds
  // checks must hold. Each is read, and if it reads, restored with --force
  // semantics into the scene; anything but CheckpointError is a failure.
  const std::string payload = good_.substr(kHeader, good_.size() - kHeader - 4);
  Scene scene = load_scene(dir_ / "scene.yaml", shipped_plugins(),
                           {{"simulation.duration", "~"}, {"simulation.steps", "200"}});
  std::mt19937 rng(8);
  std::uniform_int_distribution<std::size_t> where(0, payload.size() - 1);
  int read = 0, refused = 0, restored = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string p = payload;
    switch (i % 4) {
      case 0:
        p[where(rng)] = static_cast<char>(rng());
        break;   // one byte
      case 1: {  // a random u64
        const std::size_t at = where(rng) % (p.size() - 8);
        const std::uint64_t v = (std::uint64_t{rng()} << 32) | rng();
        std::memcpy(p.data() + at, &v, 8);
        break;
      }
      case 2: {  // a huge length
        const std::size_t at = where(rng) % (p.size() - 8);
        const std::uint64_t v = ~std::uint64_t{0} - (rng() % 64);
        std::memcpy(p.data() + at, &v, 8);
        break;
      }
      case 3:
        p.resize(where(rng));
        break;  // cut short
    }
    write_bytes(dir_ / "resealed.ckpt", reseal(good_, p));
    try {
      const Checkpoint c = read_checkpoint(dir_ / "resealed.ckpt");
      ++read;
      restore_checkpoint(scene, c, /*force=*/true);
      ++restored;
    } catch (const CheckpointError&) {
      ++refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "case " << i << ": " << typeid(e).name() << ": " << e.what();
    }
  }
  std::cout << "resealed payloads: " << refused << " refused, " << read << " read, " << restored
            << " restored\n";
  EXPECT_GT(refused, 500);
  EXPECT_GT(restored, 500);
}

}  // namespace
}  // namespace pdyn
