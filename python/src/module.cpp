// _pdyn: the compiled half of the pdyn Python package (python/pdyn/ holds
// the other half, and the API users import).
#include "bindings.hpp"
#include "pdyn/host/version.hpp"
#include "pdyn/version.hpp"

PYBIND11_MODULE(_pdyn, m) {
  m.doc() = "pdyn's C++ core; import pdyn, not this module";
  m.attr("version") = pdyn::host::version();
  m.attr("abi_version") = pdyn::kAbiVersion;
  pdyn::python::bind_errors(m);
  pdyn::python::bind_simulation(m);
  pdyn::python::bind_plugins(m);
  pdyn::python::bind_python_force(m);
}
