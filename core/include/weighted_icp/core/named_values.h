// Values read by name (a command-line choice, a config token): one lookup and one error form for every enum.
#pragma once

#include <initializer_list>
#include <stdexcept>
#include <string>

namespace weighted_icp {

/// @brief The value among `values` whose name is `name`.
/// @param name    the name read
/// @param values  every value, in the order the error message lists them
/// @param name_of the name of a value (the enum's toString or ...Name function)
/// @param what    what is being named, for the message ("matcher", "PnP method")
/// @throws std::invalid_argument "unknown <what> '<name>' (expected a, b or c)" when no value has that name
template <typename Value, typename NameOf>
Value parseNamedValue(const std::string& name, std::initializer_list<Value> values, NameOf name_of,
                      const std::string& what) {
  std::string expected;
  std::size_t listed = 0;
  for (const Value value : values) {
    const std::string candidate = name_of(value);
    if (candidate == name) return value;
    expected += (listed == 0 ? "" : listed + 1 == values.size() ? " or " : ", ") + candidate;
    ++listed;
  }
  throw std::invalid_argument("unknown " + what + " '" + name + "' (expected " + expected + ")");
}

}  // namespace weighted_icp
