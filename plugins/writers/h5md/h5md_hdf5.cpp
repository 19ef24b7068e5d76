// The h5md writer's HDF5 part, libpdyn_h5md_hdf5.so (loaded by h5md.cpp on
// first use): H5MD 1.1 (de Buyl, Colberg and Hoefling, Comput. Phys.
// Commun. 185, 1546 (2014); nongnu.org/h5md) through the HDF5 C library.
//
//   /h5md                 version [1, 1]; author (name), creator (name, version)
//   /particles/all/box    dimension 3, boundary "periodic"|"none" per axis,
//                         edges [3] (m) when the scene has a simulation box
//   /particles/all/position|velocity|force|image
//                         time-dependent: step int64[F], time float64[F],
//                         value [F][N][3], chunked one frame per chunk,
//                         optionally gzip-compressed (with byte shuffling)
//   /particles/all/id|mass|fixed|radius|species   time-independent [N]
//   /connectivity/all/springs                     int64[P][2], the pairs forces join
//                                                 (proposal 103), particles_group /particles/all
//
// Atomicity: the file is written as PATH.tmp-PID and renamed when closed at
// the end of the run. Resume: the mark is the number of frames; a resumed
// run copies the file the interrupted run left (final or temporary), cuts
// every time-dependent dataset back to that many frames and goes on, so
// the datasets end as an uninterrupted run's.
#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <optional>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>
#include <utility>

namespace {

namespace fs = std::filesystem;

// Before the first HDF5 call: no clean-up of HDF5 at exit (a file whose
// closing failed, on a full disk, would be closed again then, and HDF5 1.10
// crashes on it; this writer closes its files itself), and no error stack
// printed (errors become exceptions naming the file).
void init_hdf5() {
  static const bool done = [] { return H5dont_atexit() >= 0; }();
  (void)done;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // per thread in a thread-safe HDF5
}

// An HDF5 identifier closed by the matching H5?close.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Id& operator=(Id&& o) noexcept {
    reset();
    id_ = std::exchange(o.id_, -1);
    close_ = o.close_;
    return *this;
  }
  ~Id() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  /// Forgets the identifier without closing it (HDF5 may crash closing a
  /// file whose writes failed).
  void release() { id_ = -1; }
  operator hid_t() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

std::string last_hdf5_error() {
  std::string text;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned n, const H5E_error2_t* e, void* out) -> herr_t {
        if (n == 0 && e->desc) *static_cast<std::string*>(out) = e->desc;
        return 0;
      },
      &text);
  return text.empty() ? "HDF5 error" : "HDF5: " + text;
}

// A time-dependent H5MD element: step, time and value datasets.
struct Element {
  Id group, step, time, value;
  hid_t type = -1;  // of value
  int components = 3;
};

class H5md final : public pdyn::Writer {
 public:
  H5md(const pdyn::WriterContext& ctx, int compression)
      : path_(ctx.path), temp_(pdyn::temporary_name(ctx.path)), compression_(compression) {
    init_hdf5();
    n_ = static_cast<hsize_t>(ctx.particles.size());
    std::error_code ec;
    if (path_.has_parent_path()) fs::create_directories(path_.parent_path(), ec);
    auto want = [&](const char* f) {
      return std::find(ctx.fields.begin(), ctx.fields.end(), f) != ctx.fields.end();
    };
    if (ctx.resuming) {
      resume(ctx);
    } else {
      create(ctx);
    }
    open_element("position", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kVelocity)) open_element("velocity", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kForce)) open_element("force", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kImage)) open_element("image", H5T_NATIVE_INT32);
  }

  ~H5md() override {
    if (failed_) abandon();
    elements_.clear();
    if (file_.ok()) {
      file_.reset();
      std::error_code ec;
      fs::remove(temp_, ec);
    }
  }

  void write(const pdyn::Frame& frame) override {
    const auto& p = frame.particles;
    const std::int64_t step = frame.step;
    const double t = frame.time();
    for (auto& [name, e] : elements_) {
      const void* data = name == "position"   ? static_cast<const void*>(p.x.data())
                         : name == "velocity" ? static_cast<const void*>(p.v.data())
                         : name == "force"    ? static_cast<const void*>(frame.force->data())
                                              : static_cast<const void*>(frame.images.data());
      append(e, step, t, data);
    }
    ++frames_;
    // Start the disk writing the frame now, in the background, so that the
    // fsync at commit() has only the last frames left to wait for. (The
    // default sec2 driver's handle is the file descriptor.)
    void* handle = nullptr;
    if (H5Fget_vfd_handle(file_, H5P_DEFAULT, &handle) >= 0 && handle) {
      ::sync_file_range(*static_cast<int*>(handle), 0, 0, SYNC_FILE_RANGE_WRITE);
    }
  }

  std::vector<std::uint8_t> mark() override {
    // A flush that fails (a full disk) fails the writer; asked again, it
    // gives the frames it completed.
    if (!failed_ && H5Fflush(file_, H5F_SCOPE_GLOBAL) < 0) fail("flush");
    std::vector<std::uint8_t> out;
    out.reserve(8);
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<std::uint8_t>(frames_ >> (8 * k)));
    return out;
  }

  void commit() override {
    if (failed_) {
      abandon();
      throw pdyn::Error(fmt::format(
          "{}: not completed: writing it failed earlier, and HDF5 cannot close a file whose "
          "writes failed (free some space and resume from the checkpoint: the run is written "
          "again from its start)",
          path_.string()));
    }
    elements_.clear();
    const bool closed = H5Fclose(file_) >= 0;
    file_ = Id();
    bool ok = closed;
    if (ok) {  // on disk before it takes the final name
      const int fd = ::open(temp_.c_str(), O_RDONLY | O_CLOEXEC);
      ok = fd >= 0 && ::fsync(fd) == 0;
      if (fd >= 0) ::close(fd);
    }
    std::error_code ec;
    if (ok) fs::rename(temp_, path_, ec);
    if (ok && !ec && resumed_) pdyn::remove_leftovers(path_);
    if (!ok || ec) {
      fs::remove(temp_, ec);
      throw pdyn::Error(
          fmt::format("{}: cannot write output file (closing it failed)", path_.string()));
    }
  }

  std::vector<fs::path> temp_files() const override { return {temp_}; }

 private:
  // After a failed write or flush: no more HDF5 calls on this file, and
  // its temporary file is removed (it cannot be trusted).
  void abandon() {
    for (auto& [name, e] : elements_) {
      e.group.release();
      e.step.release();
      e.time.release();
      e.value.release();
    }
    elements_.clear();
    file_.release();
    std::error_code ec;
    fs::remove(temp_, ec);
  }
  [[noreturn]] void fail(const char* what) {
    failed_ = true;
    throw pdyn::Error(fmt::format("{}: cannot write output file ({} failed: {})", path_.string(),
                                  what, last_hdf5_error()));
  }
  static Id group(hid_t parent, const char* name) {
    return Id(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  }
  void string_attribute(hid_t at, const char* name, const std::string& value) {
    Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type, value.size());
    H5Tset_strpad(type, H5T_STR_NULLPAD);
    Id space(H5Screate(H5S_SCALAR), H5Sclose);
    Id a(H5Acreate2(at, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!a.ok() || H5Awrite(a, type, value.data()) < 0) fail("writing an attribute");
  }
  template <class T>
  void array_attribute(hid_t at, const char* name, hid_t type, const std::vector<T>& values) {
    const hsize_t dims[1] = {values.size()};
    Id space(H5Screate_simple(1, dims, nullptr), H5Sclose);
    Id a(H5Acreate2(at, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!a.ok() || H5Awrite(a, type, values.data()) < 0) fail("writing an attribute");
  }
  // A fixed dataset [rows] or [rows][cols].
  void dataset(hid_t at, const char* name, hid_t type, hsize_t rows, hsize_t cols,
               const void* data) {
    const hsize_t dims[2] = {rows, cols};
    Id space(H5Screate_simple(cols > 0 ? 2 : 1, dims, nullptr), H5Sclose);
    Id d(H5Dcreate2(at, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    if (!d.ok() || (rows > 0 && H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)) {
      fail("writing a dataset");
    }
  }
  // step, time, value of one time-dependent element, empty.
  void create_element(hid_t particles, const char* name, hid_t type) {
    Id g = group(particles, name);
    const hsize_t zero[3] = {0, n_, 3}, unlimited[3] = {H5S_UNLIMITED, n_, 3};
    const hsize_t chunk[3] = {1, std::max<hsize_t>(n_, 1), 3};
    Id space(H5Screate_simple(3, zero, unlimited), H5Sclose);
    Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(props, 3, chunk);
    if (compression_ > 0) {
      H5Pset_shuffle(props);
      H5Pset_deflate(props, static_cast<unsigned>(compression_));
    }
    Id v(H5Dcreate2(g, "value", type, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose);
    const hsize_t zero1[1] = {0}, unlimited1[1] = {H5S_UNLIMITED}, chunk1[1] = {128};
    Id space1(H5Screate_simple(1, zero1, unlimited1), H5Sclose);
    Id props1(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(props1, 1, chunk1);
    Id s(H5Dcreate2(g, "step", H5T_NATIVE_INT64, space1, H5P_DEFAULT, props1, H5P_DEFAULT),
         H5Dclose);
    Id t(H5Dcreate2(g, "time", H5T_NATIVE_DOUBLE, space1, H5P_DEFAULT, props1, H5P_DEFAULT),
         H5Dclose);
    if (!g.ok() || !v.ok() || !s.ok() || !t.ok()) fail("creating a dataset");
    string_attribute(t, "unit", "s");
    if (std::string(name) != "image") {
      string_attribute(v, "unit",
                       std::string(name) == "position"   ? "m"
                       : std::string(name) == "velocity" ? "m s-1"
                                                         : "N");
    }
  }

  void create(const pdyn::WriterContext& ctx) {
    file_ = Id(H5Fcreate(temp_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!file_.ok()) {
      throw pdyn::Error(
          fmt::format("{}: cannot create output file ({})", path_.string(), last_hdf5_error()));
    }
    Id h5md = group(file_, "h5md");
    array_attribute(h5md, "version", H5T_NATIVE_INT, std::vector<int>{1, 1});
    Id author = group(h5md, "author");
    string_attribute(author, "name", "pdyn user");
    Id creator = group(h5md, "creator");
    string_attribute(creator, "name", "pdyn");
    string_attribute(creator, "version", "h5md writer 1.0.0");
    Id particles = group(file_, "particles");
    Id all = group(particles, "all");
    Id box = group(all, "box");
    {  // a scalar (H5MD: "dimension: Integer[]")
      const int three = 3;
      Id space(H5Screate(H5S_SCALAR), H5Sclose);
      Id a(H5Acreate2(box, "dimension", H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
      if (!a.ok() || H5Awrite(a, H5T_NATIVE_INT, &three) < 0) fail("writing an attribute");
    }
    {
      const auto& d = ctx.particles.domain;
      Id type(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(type, 8);
      H5Tset_strpad(type, H5T_STR_NULLPAD);
      char boundary[3][8] = {};
      for (int k = 0; k < 3; ++k) {
        const std::string b = d.periodic[k] ? "periodic" : "none";
        std::copy(b.begin(), b.end(), boundary[k]);
      }
      const hsize_t dims[1] = {3};
      Id space(H5Screate_simple(1, dims, nullptr), H5Sclose);
      Id a(H5Acreate2(box, "boundary", type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
      if (!a.ok() || H5Awrite(a, type, boundary) < 0) fail("writing an attribute");
      const pdyn::Vec3 length = d.length();
      if (length.minCoeff() > 0) dataset(box, "edges", H5T_NATIVE_DOUBLE, 3, 0, length.data());
    }
    const auto& p = ctx.particles;
    auto want = [&](const char* f) {
      return std::find(ctx.fields.begin(), ctx.fields.end(), f) != ctx.fields.end();
    };
    if (want(pdyn::field::kId)) {
      std::vector<std::int64_t> ids(n_);
      for (hsize_t i = 0; i < n_; ++i) ids[i] = static_cast<std::int64_t>(i);
      dataset(all, "id", H5T_NATIVE_INT64, n_, 0, ids.data());
    }
    if (want(pdyn::field::kMass)) dataset(all, "mass", H5T_NATIVE_DOUBLE, n_, 0, p.mass.data());
    if (want(pdyn::field::kFixed)) dataset(all, "fixed", H5T_NATIVE_UINT8, n_, 0, p.fixed.data());
    if (want(pdyn::field::kRadius) && !p.radius.empty()) {
      dataset(all, "radius", H5T_NATIVE_DOUBLE, n_, 0, p.radius.data());
    }
    if (want(pdyn::field::kType) && !p.type.empty()) {
      dataset(all, "species", H5T_NATIVE_INT32, n_, 0, p.type.data());
    }
    create_element(all, "position", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kVelocity)) create_element(all, "velocity", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kForce)) create_element(all, "force", H5T_NATIVE_DOUBLE);
    if (want(pdyn::field::kImage)) create_element(all, "image", H5T_NATIVE_INT32);
    if (!ctx.pairs.empty()) {
      Id connectivity = group(file_, "connectivity");
      Id group_all = group(connectivity, "all");
      std::vector<std::int64_t> pairs;
      for (const auto& q : ctx.pairs) pairs.insert(pairs.end(), {q[0], q[1]});
      dataset(group_all, "springs", H5T_NATIVE_INT64, ctx.pairs.size(), 2, pairs.data());
      Id springs(H5Dopen2(group_all, "springs", H5P_DEFAULT), H5Dclose);
      hobj_ref_t ref;
      if (H5Rcreate(&ref, file_, "/particles/all", H5R_OBJECT, -1) < 0) fail("a reference");
      Id space(H5Screate(H5S_SCALAR), H5Sclose);
      Id a(H5Acreate2(springs, "particles_group", H5T_STD_REF_OBJ, space, H5P_DEFAULT, H5P_DEFAULT),
           H5Aclose);
      if (!a.ok() || H5Awrite(a, H5T_STD_REF_OBJ, &ref) < 0) fail("writing an attribute");
    }
  }

  // Copies the file an interrupted run left and cuts it back to the mark.
  void resume(const pdyn::WriterContext& ctx) {
    if (ctx.resume.size() != 8) {
      throw pdyn::ResumeError(
          fmt::format("{}: an h5md mark of {} bytes (expected 8: the number of frames)",
                      path_.string(), ctx.resume.size()));
    }
    std::uint64_t frames = 0;
    for (int k = 0; k < 8; ++k) frames |= static_cast<std::uint64_t>(ctx.resume[k]) << (8 * k);
    std::vector<fs::path> candidates{path_};
    for (auto& c : pdyn::leftover_temporaries(path_)) candidates.push_back(std::move(c));
    for (const auto& c : candidates) {
      std::error_code ec;
      if (!fs::is_regular_file(c, ec)) continue;
      fs::copy_file(c, temp_, fs::copy_options::overwrite_existing, ec);
      if (ec) continue;
      file_ = Id(H5Fopen(temp_.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
      if (file_.ok() && cut_to(frames)) {
        frames_ = frames;
        resumed_ = true;
        return;
      }
      file_ = Id();
    }
    fs::remove(temp_);
    throw pdyn::ResumeError(fmt::format(
        "{}: cannot resume this output: no file holds the {} frames the checkpoint recorded "
        "(expected the file written by the interrupted run)",
        path_.string(), frames));
  }
  bool cut_to(std::uint64_t frames) {
    Id all(H5Gopen2(file_, "/particles/all", H5P_DEFAULT), H5Gclose);
    if (!all.ok()) return false;
    for (const char* name : {"position", "velocity", "force", "image"}) {
      if (H5Lexists(all, name, H5P_DEFAULT) <= 0) continue;
      Id g(H5Gopen2(all, name, H5P_DEFAULT), H5Gclose);
      for (const char* d : {"step", "time", "value"}) {
        Id set(H5Dopen2(g, d, H5P_DEFAULT), H5Dclose);
        if (!set.ok()) return false;
        Id space(H5Dget_space(set), H5Sclose);
        hsize_t dims[3] = {0, 0, 0};
        const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
        if (rank < 1 || dims[0] < frames) return false;
        dims[0] = frames;
        if (H5Dset_extent(set, dims) < 0) return false;
      }
    }
    return true;
  }

  void open_element(const char* name, hid_t type) {
    const std::string base = std::string("/particles/all/") + name;
    if (H5Lexists(file_, base.c_str(), H5P_DEFAULT) <= 0) {
      throw pdyn::ResumeError(fmt::format(
          "{}: cannot resume this output: it has no {} (expected the file written by the "
          "interrupted run)",
          path_.string(), base));
    }
    Element e;
    e.group = Id(H5Gopen2(file_, base.c_str(), H5P_DEFAULT), H5Gclose);
    e.step = Id(H5Dopen2(e.group, "step", H5P_DEFAULT), H5Dclose);
    e.time = Id(H5Dopen2(e.group, "time", H5P_DEFAULT), H5Dclose);
    e.value = Id(H5Dopen2(e.group, "value", H5P_DEFAULT), H5Dclose);
    e.type = type;
    if (!e.step.ok() || !e.time.ok() || !e.value.ok()) fail("opening a dataset");
    elements_.emplace_back(name, std::move(e));
  }

  void append(Element& e, std::int64_t step, double t, const void* value) {
    const hsize_t k = frames_;
    auto put = [&](hid_t set, int rank, const hsize_t* size, hid_t type, const void* data) {
      hsize_t dims[3] = {k + 1, n_, 3}, start[3] = {k, 0, 0}, count[3] = {1, n_, 3};
      (void)size;
      if (H5Dset_extent(set, dims) < 0) fail("extending a dataset");
      Id file_space(H5Dget_space(set), H5Sclose);
      H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr);
      Id memory(H5Screate_simple(rank, count, nullptr), H5Sclose);
      if (H5Dwrite(set, type, memory, file_space, H5P_DEFAULT, data) < 0) fail("writing a frame");
    };
    put(e.value, 3, nullptr, e.type, value);
    put(e.step, 1, nullptr, H5T_NATIVE_INT64, &step);
    put(e.time, 1, nullptr, H5T_NATIVE_DOUBLE, &t);
  }

  fs::path path_, temp_;
  int compression_;
  hsize_t n_ = 0;
  Id file_;
  std::vector<std::pair<std::string, Element>> elements_;
  std::uint64_t frames_ = 0;
  bool failed_ = false;
  bool resumed_ = false;  // commit removes what the interrupted run left
};

// ---- the reader (pdyn check): position and velocity of every frame ----

std::vector<pdyn::FrameRecord> read_back(const fs::path& path) {
  init_hdf5();
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok())
    throw pdyn::Error(fmt::format("{}: cannot open ({})", path.string(), last_hdf5_error()));
  auto read = [&](const char* name, std::vector<double>& out, hsize_t* dims) -> bool {
    if (H5Lexists(file, name, H5P_DEFAULT) <= 0) return false;
    Id set(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
    Id space(H5Dget_space(set), H5Sclose);
    const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
    hsize_t total = 1;
    for (int k = 0; k < rank; ++k) total *= dims[k];
    out.resize(total);
    return H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0;
  };
  std::vector<double> t, x, v;
  hsize_t td[3] = {}, xd[3] = {}, vd[3] = {};
  if (!read("/particles/all/position/time", t, td) ||
      !read("/particles/all/position/value", x, xd)) {
    throw pdyn::Error(fmt::format("{}: no /particles/all/position", path.string()));
  }
  const bool has_v = read("/particles/all/velocity/value", v, vd);
  std::vector<pdyn::FrameRecord> frames(td[0]);
  const auto n = static_cast<pdyn::Index>(xd[1]);
  for (hsize_t k = 0; k < td[0]; ++k) {
    frames[k].time = t[k];
    frames[k].x = Eigen::Map<const pdyn::Matrix3X>(x.data() + k * 3 * n, 3, n);
    if (has_v) frames[k].v = Eigen::Map<const pdyn::Matrix3X>(v.data() + k * 3 * n, 3, n);
  }
  return frames;
}

}  // namespace

// The two entry points h5md.cpp looks up when a scene first asks for the
// writer or `pdyn check` reads a file back.
extern "C" PDYN_PLUGIN_EXPORT pdyn::Writer* pdyn_h5md_create_writer(
    const pdyn::Params& p, const pdyn::WriterContext& ctx) {
  return new H5md(ctx, static_cast<int>(p.integer("compression")));
}

extern "C" PDYN_PLUGIN_EXPORT void pdyn_h5md_read_back(const std::filesystem::path& path,
                                                       std::vector<pdyn::FrameRecord>& out) {
  out = read_back(path);
}
