#include "weighted_icp/registration/point_field_weights.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace weighted_icp {

namespace {
template <typename T>
double load(const std::uint8_t* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));  // fields need not be aligned
  return static_cast<double>(value);
}
}  // namespace

double readScalarField(const std::uint8_t* point_bytes, const pcl::PCLPointField& field) {
  const std::uint8_t* bytes = point_bytes + field.offset;
  switch (field.datatype) {
    case pcl::PCLPointField::INT8: return load<std::int8_t>(bytes);
    case pcl::PCLPointField::UINT8: return load<std::uint8_t>(bytes);
    case pcl::PCLPointField::INT16: return load<std::int16_t>(bytes);
    case pcl::PCLPointField::UINT16: return load<std::uint16_t>(bytes);
    case pcl::PCLPointField::INT32: return load<std::int32_t>(bytes);
    case pcl::PCLPointField::UINT32: return load<std::uint32_t>(bytes);
    case pcl::PCLPointField::FLOAT32: return load<float>(bytes);
    case pcl::PCLPointField::FLOAT64: return load<double>(bytes);
    default: throw std::invalid_argument("point field '" + field.name + "' is not a numeric scalar");
  }
}

void checkWeights(const std::vector<double>& weights, const std::string& what) {
  for (std::size_t i = 0; i < weights.size(); ++i) {
    if (!std::isfinite(weights[i]) || weights[i] < 0.0)
      throw std::invalid_argument(what + ": weight " + std::to_string(i) + " is " + std::to_string(weights[i]) +
                                  "; weights must be finite and >= 0");
  }
}

}  // namespace weighted_icp
