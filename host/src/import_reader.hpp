// What the readers of other programs' particle files share (private to
// import_files.cpp, import_lammps_data.cpp, import_lammps_dump.cpp and
// import_xyz.cpp): the atom as a reader collects it, its conversion to the
// loader's rows (sorted by id, duplicates refused), the box, and the choice
// of a frame. Fields, numbers and problems are text_file.hpp's, as for the
// CSV side files.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "import_files.hpp"
#include "text_file.hpp"

namespace pdyn::import_files::detail {

using text_file::Field;
using text_file::Line;
using text_file::parse_real;
using text_file::parse_whole;
using text_file::Problems;
using text_file::quoted;

/// One particle as a reader collects it, before the sort by id.
struct Atom {
  long long id = 0;
  long long type = 1;      ///< LAMMPS's type (>= 1); for XYZ the species' index + 1
  std::uint32_t kind = 0;  ///< index into Imported::kinds
  Vec3 x = Vec3::Zero(), v = Vec3::Zero();
  double mass = 0.0, radius = -1.0;  ///< radius < 0: not given
  std::array<std::int32_t, 3> image{};
};

/// The atoms of a file and the line each came from.
struct Atoms {
  std::vector<Atom> atoms;
  std::vector<std::size_t> lines;
  void add(const Atom& a, std::size_t line) {
    atoms.push_back(a);
    lines.push_back(line);
  }
};

/// An image flag along `axis` (0, 1, 2: x, y, z) read from `f`, or a problem at it.
std::optional<std::int32_t> parse_image(const Field& f, std::size_t line, int axis,
                                        Problems& problems);

/// Where a row of a dump or XYZ file has the columns besides its id, type
/// and position (-1: absent): velocity, mass, radius or diameter.
struct MoreColumns {
  std::array<int, 3> v{-1, -1, -1};
  int mass = -1, radius = -1;
  bool diameter = false;  ///< the radius column holds the diameter
};

/// Reads those columns of `fields` into `a`; false after a problem.
bool read_more(const std::vector<Field>& fields, std::size_t line, const MoreColumns& c, Atom& a,
               Problems& problems);

/// Gives LAMMPS atoms their kinds: the types 1..declared (a data file's
/// header) and any other type present, in numeric order, as text.
void lammps_kinds(Atoms& atoms, long long declared, Imported& out);

/// Sorts by id, refuses duplicate ids (at their lines), and fills out.rows
/// (types as Atom::type, or the kind's index for XYZ species) and, with
/// `images`, out.images. False if a problem was found.
bool to_rows(Atoms& in, bool images, Problems& problems, Imported& out);

/// The box [lo, hi] with its periodic axes.
Domain orthogonal_box(const Vec3& lo, const Vec3& hi, const std::array<bool, 3>& periodic);

/// Which of a file's frames to read, given each frame's first line
/// (`starts`): frame `frame`, 0 the first, -1 the last. Records the count in
/// `r`. Nothing if the file has no frame (`empty` reported at line 1) or no
/// such frame (r.no_such_frame set: the loader reports it at `frame:`).
std::optional<std::size_t> choose_frame(const std::vector<std::size_t>& starts, long long frame,
                                        std::string_view empty, Problems& problems, ReadResult& r);

/// A mass read from `f` that must be > 0, or a problem at it.
std::optional<double> parse_mass(const Field& f, std::size_t line, Problems& problems);

/// A length read from `f` that must be >= 0 (a radius or a diameter).
std::optional<double> parse_size(const Field& f, std::size_t line, std::string_view name,
                                 Problems& problems);

/// `atom_style` as import_files::read() takes it (empty: the title's comment).
ReadResult read_lammps_data(const std::string& text, std::string_view atom_style,
                            Problems& problems);
ReadResult read_lammps_dump(const std::string& text, long long frame, Problems& problems);
ReadResult read_extxyz(const std::string& text, long long frame, Problems& problems);

}  // namespace pdyn::import_files::detail
