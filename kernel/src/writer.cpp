// The field names of pdyn/writer.hpp.
#include "pdyn/writer.hpp"

namespace pdyn {

const std::vector<std::string>& known_fields() {
  static const std::vector<std::string> names = {field::kVelocity, field::kMass, field::kFixed,
                                                 field::kRadius,   field::kType, field::kForce,
                                                 field::kImage,    field::kId};
  return names;
}

}  // namespace pdyn
