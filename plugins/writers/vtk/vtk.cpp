// The vtk writer: a ParaView collection (PATH.pvd) of one VTK XML PolyData
// file per frame (PATH-without-.pvd/STEM_NNNNNN.vtp), with the obstacles of
// the colliders in a second file (obstacles.vtp) listed beside each frame
// as part 1, so ParaView shows them as a second block.
//
// A frame file holds the particles as points with one vertex each, the
// particle pairs that forces join (springs) as lines and the triples
// (angles, areas) as polygons, and the requested point data, all as raw
// little-endian binary in the appended data section (header_type UInt64:
// each array is preceded by its length in bytes, and its DataArray element
// names its offset from the first byte after the '_'). Doubles are written
// as Float64, so every value reads back bit for bit.
//
// Atomicity: each .vtp is written under a temporary name and renamed when
// complete; the .pvd is an OutputFile (pdyn/output_file.hpp), renamed with
// its closing tags at commit. Resume: the mark is the .pvd's (bytes, CRC)
// and the number of frames; frame files from an interrupted run past that
// number are removed, and numbering goes on from it.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <pdyn/output_file.hpp>
#include <pdyn/plugin.hpp>
#include <sstream>

namespace {

namespace fs = std::filesystem;

// One DataArray of the appended section.
struct Array {
  const char* name;
  const char* type;  // Float64, Int64, Int32, UInt8
  int components;
  const void* data;
  std::uint64_t bytes;
};

// A PolyData file of points, verts, lines and polys and point/cell data,
// with raw appended data. `out` is reused between frames.
void write_polydata(std::vector<char>& out, std::uint64_t n_points, const Array& points,
                    std::uint64_t n_verts, const Array* verts, std::uint64_t n_lines,
                    const Array* lines, std::uint64_t n_polys, const Array* polys,
                    const std::vector<Array>& point_data, const std::vector<Array>& cell_data,
                    const std::string& comment) {
  out.clear();
  std::uint64_t offset = 0;
  std::string xml;
  auto element = [&](const Array& a) {
    xml += fmt::format(
        "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" "
        "offset=\"{}\"/>\n",
        a.type, a.name, a.components, offset);
    offset += sizeof(std::uint64_t) + a.bytes;
  };
  xml += "<?xml version=\"1.0\"?>\n";
  if (!comment.empty()) xml += fmt::format("<!-- {} -->\n", comment);
  xml +=
      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n  <PolyData>\n";
  xml += fmt::format(
      "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"{}\" "
      "NumberOfStrips=\"0\" NumberOfPolys=\"{}\">\n",
      n_points, n_verts, n_lines, n_polys);
  std::vector<const Array*> order;
  xml += "      <PointData>\n";
  for (const auto& a : point_data) {
    element(a);
    order.push_back(&a);
  }
  xml += "      </PointData>\n      <CellData>\n";
  for (const auto& a : cell_data) {
    element(a);
    order.push_back(&a);
  }
  xml += "      </CellData>\n      <Points>\n";
  element(points);
  order.push_back(&points);
  xml += "      </Points>\n";
  const std::pair<const char*, const Array*> cells[] = {
      {"Verts", verts}, {"Lines", lines}, {"Polys", polys}};
  for (const auto& [tag, pair] : cells) {
    xml += fmt::format("      <{}>\n", tag);
    if (pair) {
      for (int k = 0; k < 2; ++k) {
        element(pair[k]);
        order.push_back(&pair[k]);
      }
    }
    xml += fmt::format("      </{}>\n", tag);
  }
  xml += "    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";
  out.reserve(xml.size() + offset + 64);
  out.insert(out.end(), xml.begin(), xml.end());
  for (const Array* a : order) {
    const char* size = reinterpret_cast<const char*>(&a->bytes);
    out.insert(out.end(), size, size + sizeof(std::uint64_t));
    const char* d = static_cast<const char*>(a->data);
    out.insert(out.end(), d, d + a->bytes);
  }
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  out.insert(out.end(), tail.begin(), tail.end());
}

// Cells of k points each: connectivity and end offsets (VTK XML 1.0),
// written as Int32 once narrow() has found that every value fits (a third
// less per frame of a cloth, whose springs are most of its bytes), else as
// Int64. VTK's reader takes either.
struct Cells {
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::int32_t> connectivity32, offsets32;  // after narrow(), when they fit
  bool narrowed = false;

  std::array<Array, 2> arrays() const {
    if (narrowed) {
      return {Array{"connectivity", "Int32", 1, connectivity32.data(), connectivity32.size() * 4},
              Array{"offsets", "Int32", 1, offsets32.data(), offsets32.size() * 4}};
    }
    return {Array{"connectivity", "Int64", 1, connectivity.data(), connectivity.size() * 8},
            Array{"offsets", "Int64", 1, offsets.data(), offsets.size() * 8}};
  }
  void add(std::initializer_list<std::int64_t> ids) {
    connectivity.insert(connectivity.end(), ids);
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  // Call once every cell is added. Offsets grow, so the last is the largest.
  void narrow() {
    constexpr std::int64_t kMax = std::numeric_limits<std::int32_t>::max();
    const bool fits = std::all_of(connectivity.begin(), connectivity.end(),
                                  [](std::int64_t i) { return i >= 0 && i <= kMax; }) &&
                      (offsets.empty() || offsets.back() <= kMax);
    if (!fits) return;
    connectivity32.assign(connectivity.begin(), connectivity.end());
    offsets32.assign(offsets.begin(), offsets.end());
    connectivity = {};
    offsets = {};
    narrowed = true;
  }
  std::uint64_t size() const { return narrowed ? offsets32.size() : offsets.size(); }
};

bool has(const std::vector<std::string>& fields, const char* f) {
  return std::find(fields.begin(), fields.end(), f) != fields.end();
}

// The obstacles as triangles and quads: planes as a square of side
// `extent` centred at the point of the plane nearest `centre`.
void obstacle_mesh(const std::vector<pdyn::Shape>& shapes, const pdyn::Vec3& centre, double extent,
                   std::vector<double>& points, Cells& polys, std::vector<std::int32_t>& which) {
  auto point = [&](const pdyn::Vec3& p) {
    points.insert(points.end(), {p.x(), p.y(), p.z()});
    return static_cast<std::int64_t>(points.size() / 3 - 1);
  };
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const auto id = static_cast<std::int32_t>(k);
    const std::size_t before = polys.size();
    if (const auto* pl = std::get_if<pdyn::shape::Plane>(&shapes[k])) {
      const pdyn::Vec3 n = pl->normal.normalized();
      const pdyn::Vec3 c = centre - (centre - pl->point).dot(n) * n;
      const pdyn::Vec3 a = n.unitOrthogonal(), b = n.cross(a);
      const double h = 0.5 * extent;
      const auto p0 = point(c - h * a - h * b), p1 = point(c + h * a - h * b);
      const auto p2 = point(c + h * a + h * b), p3 = point(c - h * a + h * b);
      polys.add({p0, p1, p2, p3});
    } else if (const auto* s = std::get_if<pdyn::shape::Sphere>(&shapes[k])) {
      constexpr int kRings = 16, kSegments = 32;
      const double pi = 3.14159265358979323846;
      const auto first = static_cast<std::int64_t>(points.size() / 3);
      for (int i = 0; i <= kRings; ++i) {
        const double th = pi * i / kRings;
        for (int j = 0; j < kSegments; ++j) {
          const double ph = 2 * pi * j / kSegments;
          point(s->center + s->radius * pdyn::Vec3(std::sin(th) * std::cos(ph),
                                                   std::sin(th) * std::sin(ph), std::cos(th)));
        }
      }
      auto at = [&](int i, int j) { return first + i * kSegments + (j % kSegments); };
      for (int i = 0; i < kRings; ++i) {
        for (int j = 0; j < kSegments; ++j) {
          polys.add({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
        }
      }
    } else if (const auto* bx = std::get_if<pdyn::shape::Box>(&shapes[k])) {
      const auto first = static_cast<std::int64_t>(points.size() / 3);
      for (int c = 0; c < 8; ++c) {
        point({c & 1 ? bx->max.x() : bx->min.x(), c & 2 ? bx->max.y() : bx->min.y(),
               c & 4 ? bx->max.z() : bx->min.z()});
      }
      const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                               {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
      for (const auto& f : faces) {
        polys.add({first + f[0], first + f[1], first + f[2], first + f[3]});
      }
    } else if (const auto* m = std::get_if<pdyn::shape::Mesh>(&shapes[k])) {
      const auto first = static_cast<std::int64_t>(points.size() / 3);
      for (const auto& v : m->vertices) point(v);
      for (const auto& t : m->triangles) polys.add({first + t[0], first + t[1], first + t[2]});
    }
    which.insert(which.end(), polys.size() - before, id);
  }
}

class Vtk final : public pdyn::Writer {
 public:
  explicit Vtk(const pdyn::WriterContext& ctx)
      : fields_(ctx.fields),
        folder_(fs::path(ctx.path).replace_extension("")),
        stem_(fs::path(ctx.path).stem().string()),
        resume_(ctx.resuming ? std::optional(decode(ctx.resume)) : std::nullopt),
        pvd_(ctx.path, resume_ ? &resume_->first : nullptr) {
    const auto n = static_cast<std::int64_t>(ctx.particles.size());
    for (std::int64_t i = 0; i < n; ++i) verts_.add({i});
    for (const auto& p : ctx.pairs) lines_.add({p[0], p[1]});
    for (const auto& t : ctx.triples) polys_.add({t[0], t[1], t[2]});
    for (Cells* c : {&verts_, &lines_, &polys_}) c->narrow();
    // Ids as Int32 too where they fit.
    if (n <= std::numeric_limits<std::int32_t>::max()) {
      ids32_.resize(static_cast<std::size_t>(n));
      for (std::int64_t i = 0; i < n; ++i)
        ids32_[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(i);
    } else {
      ids_.resize(static_cast<std::size_t>(n));
      for (std::int64_t i = 0; i < n; ++i) ids_[static_cast<std::size_t>(i)] = i;
    }
    std::error_code ec;
    fs::create_directories(folder_, ec);
    if (ec) {
      throw pdyn::Error(fmt::format("{}: cannot create the folder of the frames ({})",
                                    folder_.string(), ec.message()));
    }
    if (resume_) {
      frames_ = resume_->second;
      last_mark_ = *resume_;
      // Frames an interrupted run wrote past the checkpoint.
      for (const auto& e : fs::directory_iterator(folder_, ec)) {
        const std::string name = e.path().filename().string();
        const std::string prefix = stem_ + "_";
        if (name.find(".vtp.tmp-") != std::string::npos) {  // a killed run's unfinished frame
          fs::remove(e.path(), ec);
          continue;
        }
        if (name.rfind(prefix, 0) != 0 || e.path().extension() != ".vtp") continue;
        const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - 4);
        if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        if (std::stoull(digits) >= frames_) fs::remove(e.path(), ec);
      }
    } else {
      pvd_.write(
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
          "  <Collection>\n");
    }
    if (!ctx.obstacles.empty()) write_obstacles(ctx);
  }

  void write(const pdyn::Frame& frame) override {
    before_ = {pvd_.written(), frames_};
    failed_ = true;
    const auto& p = frame.particles;
    const auto n = static_cast<std::uint64_t>(p.size());
    std::vector<Array> data;
    if (has(fields_, pdyn::field::kId)) {
      data.push_back(ids_.empty() ? Array{"id", "Int32", 1, ids32_.data(), n * 4}
                                  : Array{"id", "Int64", 1, ids_.data(), n * 8});
    }
    if (has(fields_, pdyn::field::kVelocity)) {
      data.push_back({"velocity", "Float64", 3, p.v.data(), 3 * n * 8});
    }
    if (has(fields_, pdyn::field::kMass))
      data.push_back({"mass", "Float64", 1, p.mass.data(), n * 8});
    if (has(fields_, pdyn::field::kFixed)) data.push_back({"fixed", "UInt8", 1, p.fixed.data(), n});
    if (has(fields_, pdyn::field::kRadius) && !p.radius.empty()) {
      data.push_back({"radius", "Float64", 1, p.radius.data(), n * 8});
    }
    if (has(fields_, pdyn::field::kType) && !p.type.empty()) {
      data.push_back({"type", "Int32", 1, p.type.data(), n * 4});
    }
    if (has(fields_, pdyn::field::kForce) && frame.force) {
      data.push_back({"force", "Float64", 3, frame.force->data(), 3 * n * 8});
    }
    if (has(fields_, pdyn::field::kImage)) {
      data.push_back({"image", "Int32", 3, frame.images.data(), 3 * n * 4});
    }
    const auto v = verts_.arrays(), l = lines_.arrays(), q = polys_.arrays();
    write_polydata(buffer_, n, {"Points", "Float64", 3, p.x.data(), 3 * n * 8}, verts_.size(),
                   v.data(), lines_.size(), lines_.size() ? l.data() : nullptr, polys_.size(),
                   polys_.size() ? q.data() : nullptr, data, {},
                   fmt::format("pdyn frame: t = {:.17g} s, step {}", frame.time(), frame.step));
    const std::string name = fmt::format("{}_{:06d}.vtp", stem_, frames_);
    pdyn::write_file_atomically(folder_ / name, buffer_);
    const std::string file = (folder_.filename() / name).generic_string();
    std::string entry =
        fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
                    frame.time(), file);
    if (has_obstacles_) {
      entry +=
          fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"1\" file=\"{}\"/>\n",
                      frame.time(), (folder_.filename() / "obstacles.vtp").generic_string());
    }
    pvd_.write(entry);
    ++frames_;
    failed_ = false;
  }

  // After a failed write, the output before that frame; after a failed
  // flush, the output at the last mark.
  std::vector<std::uint8_t> mark() override {
    if (!failed_) {
      failed_ = true;
      before_ = last_mark_;
      last_mark_ = {pvd_.mark(), frames_};
      failed_ = false;
    }
    const auto [file, frames] = failed_ ? before_ : last_mark_;
    std::vector<std::uint8_t> out = file.encode();
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<std::uint8_t>(frames >> (8 * k)));
    return out;
  }
  void commit() override {
    static constexpr std::string_view kTail = "  </Collection>\n</VTKFile>\n";
    if (failed_) {
      pvd_.commit_at(before_.first, kTail);
    } else {
      pvd_.write(kTail);
      pvd_.commit();
    }
  }
  std::vector<fs::path> temp_files() const override { return {pvd_.temp_path()}; }

 private:
  static std::pair<pdyn::FileMark, std::uint64_t> decode(const std::vector<std::uint8_t>& m) {
    if (m.size() != 20) {
      throw pdyn::ResumeError(fmt::format(
          "a vtk writer's mark of {} bytes (expected 20: the .pvd's length and CRC-32, and the "
          "number of frames)",
          m.size()));
    }
    std::uint64_t frames = 0;
    for (int k = 0; k < 8; ++k) frames |= static_cast<std::uint64_t>(m[12 + k]) << (8 * k);
    return {pdyn::FileMark::decode(std::span(m).first(12)), frames};
  }

  void write_obstacles(const pdyn::WriterContext& ctx) {
    // Planes are drawn as squares twice the particles' extent, around them.
    const auto& x = ctx.particles.x;
    pdyn::Vec3 centre = pdyn::Vec3::Zero();
    double extent = 2.0;
    if (x.cols() > 0) {
      const pdyn::Vec3 lo = x.rowwise().minCoeff(), hi = x.rowwise().maxCoeff();
      centre = 0.5 * (lo + hi);
      extent = std::max(2.0 * (hi - lo).maxCoeff(), 2.0);
    }
    std::vector<double> points;
    Cells polys;
    std::vector<std::int32_t> which;
    obstacle_mesh(ctx.obstacles, centre, extent, points, polys, which);
    polys.narrow();
    const auto q = polys.arrays();
    std::vector<char> buf;
    const std::uint64_t np = points.size() / 3;
    write_polydata(buf, np, {"Points", "Float64", 3, points.data(), points.size() * 8}, 0, nullptr,
                   0, nullptr, polys.size(), q.data(), {},
                   {{"obstacle", "Int32", 1, which.data(), which.size() * 4}},
                   "pdyn obstacles: the colliders' shapes (cell data: which collider shape)");
    pdyn::write_file_atomically(folder_ / "obstacles.vtp", buf);
    has_obstacles_ = true;
  }

  std::vector<std::string> fields_;
  fs::path folder_;
  std::string stem_;
  std::optional<std::pair<pdyn::FileMark, std::uint64_t>> resume_;
  pdyn::OutputFile pvd_;
  Cells verts_, lines_, polys_;
  std::vector<std::int64_t> ids_;    // more than 2^31 - 1 particles
  std::vector<std::int32_t> ids32_;  // else
  std::vector<char> buffer_;
  std::uint64_t frames_ = 0;
  bool has_obstacles_ = false;
  std::pair<pdyn::FileMark, std::uint64_t> before_, last_mark_;
  bool failed_ = false;
};

// ---- the reader (pdyn check): this writer's own files, not VTK in general ----

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw pdyn::Error(fmt::format("{}: cannot read", p.string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const auto at = tag.find(key);
  if (at == std::string::npos) return {};
  const auto begin = at + key.size();
  return tag.substr(begin, tag.find('"', begin) - begin);
}

// The Float64 3-component array `name` of a .vtp written by this plugin.
pdyn::Matrix3X read_vectors(const std::string& text, const std::string& name, const fs::path& p) {
  const auto data = text.find("<AppendedData encoding=\"raw\">");
  const auto underscore = text.find('_', data);
  const auto element = text.find("Name=\"" + name + "\"");
  if (data == std::string::npos || underscore == std::string::npos) {
    throw pdyn::Error(fmt::format("{}: no raw appended data", p.string()));
  }
  if (element == std::string::npos || element > data) return {};
  const auto start = text.rfind('<', element), end = text.find('>', element);
  const std::string tag = text.substr(start, end - start);
  const std::uint64_t offset = std::stoull(attribute(tag, "offset"));
  std::uint64_t bytes = 0;
  const std::size_t at = underscore + 1 + offset;
  if (at + 8 > text.size()) throw pdyn::Error(fmt::format("{}: truncated", p.string()));
  std::memcpy(&bytes, text.data() + at, 8);
  if (at + 8 + bytes > text.size() || bytes % 24 != 0) {
    throw pdyn::Error(fmt::format("{}: array {} is truncated", p.string(), name));
  }
  pdyn::Matrix3X m(3, static_cast<pdyn::Index>(bytes / 24));
  std::memcpy(m.data(), text.data() + at + 8, bytes);
  return m;
}

std::vector<pdyn::FrameRecord> read_back(const fs::path& path) {
  const std::string pvd = read_all(path);
  std::vector<pdyn::FrameRecord> frames;
  for (std::size_t at = 0; (at = pvd.find("<DataSet ", at)) != std::string::npos; ++at) {
    const std::string tag = pvd.substr(at, pvd.find('>', at) - at);
    if (attribute(tag, "part") != "0") continue;
    const fs::path file = path.parent_path() / attribute(tag, "file");
    const std::string text = read_all(file);
    pdyn::FrameRecord f;
    f.time = std::strtod(attribute(tag, "timestep").c_str(), nullptr);
    f.x = read_vectors(text, "Points", file);
    f.v = read_vectors(text, "velocity", file);
    frames.push_back(std::move(f));
  }
  return frames;
}

pdyn::PluginDescriptor describe() {
  pdyn::PluginDescriptor d;
  d.kind = pdyn::PluginKind::Writer;
  d.name = "vtk";
  d.version = "1.0.0";
  d.description =
      "ParaView collection (.pvd) of VTK XML PolyData frames (.vtp): particles, springs as "
      "lines, triples as polygons, obstacles; raw binary, Float64";
  namespace f = pdyn::field;
  d.writer_traits.fields = {f::kId,     f::kVelocity, f::kMass,  f::kFixed,
                            f::kRadius, f::kType,     f::kForce, f::kImage};
  d.writer_traits.default_fields = {f::kId,    f::kVelocity, f::kMass,
                                    f::kFixed, f::kRadius,   f::kType};
  d.create_writer = [](const pdyn::Params&, const pdyn::WriterContext& ctx) {
    return std::make_unique<Vtk>(ctx);
  };
  d.read_back = read_back;
  return d;
}

}  // namespace

PDYN_PLUGIN(describe)
