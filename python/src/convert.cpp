// Conversions between Python objects and pdyn's values (convert.hpp).
#include "convert.hpp"

#include <fmt/format.h>
#include <pybind11/stl.h>

namespace pdyn::python {

py::array view(const double* data, std::vector<py::ssize_t> shape, py::handle base, bool readonly) {
  std::vector<py::ssize_t> strides(shape.size(), sizeof(double));
  if (shape.size() == 2) strides[0] = shape[1] * static_cast<py::ssize_t>(sizeof(double));
  // An empty store may have no buffer: NumPy then gets one of its own.
  static const double empty = 0.0;
  py::array a(py::dtype::of<double>(), shape, strides, data ? data : &empty, base);
  if (readonly) set_readonly(a);
  return a;
}

py::array bool_view(const std::uint8_t* data, py::ssize_t n, py::handle base) {
  static const std::uint8_t empty = 0;
  py::array a(py::dtype("bool"), {n}, {py::ssize_t{1}}, data ? data : &empty, base);
  set_readonly(a);
  return a;
}

void set_readonly(py::handle array) {
  py::detail::array_proxy(array.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
}

namespace {

template <std::size_t K>
py::array_t<std::int64_t> index_rows(const std::vector<std::array<Index, K>>& rows) {
  py::array_t<std::int64_t> a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(K)});
  auto m = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t k = 0; k < K; ++k) m(i, k) = rows[i][k];
  }
  return a;
}

}  // namespace

py::object to_python(const ParamValue& value) {
  return std::visit(
      [](const auto& v) -> py::object {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, Vec3>) {
          return py::make_tuple(v(0), v(1), v(2));
        } else if constexpr (std::is_same_v<T, std::vector<double>>) {
          return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
        } else if constexpr (std::is_same_v<T, std::vector<Vec3>>) {
          py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
          auto m = a.mutable_unchecked<2>();
          for (std::size_t i = 0; i < v.size(); ++i) {
            for (int k = 0; k < 3; ++k) m(i, k) = v[i](k);
          }
          return a;
        } else if constexpr (std::is_same_v<T, std::vector<Index>> ||
                             std::is_same_v<T, IntegerValues>) {
          return py::array_t<std::int64_t>(static_cast<py::ssize_t>(v.size()), v.data());
        } else if constexpr (std::is_same_v<T, std::vector<IndexPair>> ||
                             std::is_same_v<T, std::vector<IndexTriple>> ||
                             std::is_same_v<T, std::vector<IndexQuad>>) {
          return index_rows(v);
        } else {
          return py::cast(v);
        }
      },
      value);
}

ParamType param_type(const std::string& name) {
  static const std::map<std::string, ParamType> names = {
      {"real", ParamType::Real},          {"integer", ParamType::Integer},
      {"boolean", ParamType::Boolean},    {"string", ParamType::String},
      {"vector", ParamType::Vector},      {"reals", ParamType::RealList},
      {"vectors", ParamType::VectorList}, {"indices", ParamType::IndexList},
      {"pairs", ParamType::IndexPairs},   {"triples", ParamType::IndexTriples},
      {"strings", ParamType::StringList}, {"named_reals", ParamType::NamedReals},
      {"quads", ParamType::IndexQuads},   {"integers", ParamType::IntegerList}};
  const auto it = names.find(name);
  if (it == names.end()) {
    std::string all;
    for (const auto& [n, t] : names) all += (all.empty() ? "" : ", ") + n;
    throw py::value_error(
        fmt::format("unknown parameter type '{}' (expected one of: {})", name, all));
  }
  return it->second;
}

ParamValue from_python(ParamType type, py::handle value, const std::string& what) {
  try {
    switch (type) {
      case ParamType::Real:
        return value.cast<double>();
      case ParamType::Integer:
        return value.cast<std::int64_t>();
      case ParamType::Boolean:
        return value.cast<bool>();
      case ParamType::String:
        return value.cast<std::string>();
      case ParamType::Vector: {
        const auto v = value.cast<std::vector<double>>();
        if (v.size() != 3) throw py::cast_error("");
        return Vec3(v[0], v[1], v[2]);
      }
      case ParamType::RealList:
        // A single number is the one-element list, as in a scene file.
        if (py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value)) {
          return std::vector<double>{value.cast<double>()};
        }
        return value.cast<std::vector<double>>();
      case ParamType::IntegerList: {
        if (py::isinstance<py::int_>(value)) {
          return IntegerValues{value.cast<std::int64_t>()};
        }
        const auto list = value.cast<std::vector<std::int64_t>>();
        return IntegerValues(list.begin(), list.end());
      }
      case ParamType::IndexQuads:
        return value.cast<std::vector<IndexQuad>>();
      case ParamType::VectorList: {
        std::vector<Vec3> out;
        for (const auto& row : value.cast<std::vector<std::vector<double>>>()) {
          if (row.size() != 3) throw py::cast_error("");
          out.emplace_back(row[0], row[1], row[2]);
        }
        return out;
      }
      case ParamType::IndexList:
        return value.cast<std::vector<Index>>();
      case ParamType::IndexPairs:
        return value.cast<std::vector<IndexPair>>();
      case ParamType::IndexTriples:
        return value.cast<std::vector<IndexTriple>>();
      case ParamType::StringList:
        return value.cast<std::vector<std::string>>();
      case ParamType::NamedReals: {
        NamedReals out;
        for (const auto& [k, v] : value.cast<std::map<std::string, double>>()) out[k] = v;
        return out;
      }
    }
  } catch (const py::cast_error&) {
  }
  throw py::type_error(fmt::format("{}: {} does not fit the type (expected a {})", what,
                                   py::repr(value).cast<std::string>(), type_name(type)));
}

}  // namespace pdyn::python
