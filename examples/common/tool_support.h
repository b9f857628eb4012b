#pragma once
// What every command-line tool of weighted_icp shares: the way it reports
// errors, range-checked numeric options, progress on long runs, JSON output
// and safe file writing.

#include <chrono>
#include <cstddef>
#include <functional>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <boost/program_options.hpp>

#include "weighted_icp/io/atomic_folder.h"

namespace weighted_icp::tools {

/// Runs a tool's body: prints "<tool>: error: <what>" to stderr and returns 1
/// on any exception, 2 on a command-line error (boost::program_options).
int runTool(const std::string& tool, const std::function<int()>& body);

/// Parses argv against `options` (which declare "help,h"), with optional
/// positional arguments. Returns false, having printed the options, when
/// --help is given; throws boost::program_options::error on a bad command line.
bool parseCommandLine(int argc, const char* const argv[], const boost::program_options::options_description& options,
                      boost::program_options::variables_map& vm,
                      const boost::program_options::positional_options_description* positional = nullptr);

namespace detail {
/// Reads all of `text` as a base-10 integer (an optional sign included); false when it is not one.
bool parseInteger(const std::string& text, long long& value);
/// Reads all of `text` as a finite number; false when it is not one.
bool parseReal(const std::string& text, double& value);
/// "between 1 and 1000", "at least 0", "greater than 0", "an integer between ...".
std::string describeRange(bool integer, double minimum, double maximum, bool minimum_exclusive);
}  // namespace detail

/// @brief Throws the command-line error (exit 2 through runTool) "--<option> must be <range> (got <value>)".
/// For bounds that depend on another option, checked after parsing; rangedValue() reports the same way.
/// @param option   the option's name without dashes
/// @param value    what was given, as typed
/// @param minimum  smallest accepted value
/// @param maximum  largest accepted value
[[noreturn]] void throwOutOfRange(const std::string& option, const std::string& value, long long minimum,
                                  long long maximum);

/// A numeric option value checked while it is parsed. Integers are read signed,
/// so "-1" is reported instead of wrapping around into a huge unsigned count;
/// floating-point values must be finite. Out of range, it throws a
/// boost::program_options error that names the option: runTool prints
/// "--k must be between 1 and 1000 (got -1)" and returns 2.
template <typename T>
class RangedValue : public boost::program_options::typed_value<T> {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "numbers only");
  using Wide = std::conditional_t<std::is_integral_v<T>, long long, double>;

 public:
  /// @brief Use rangedValue() or positiveValue() rather than this.
  /// @param store              where the parsed value goes (may be null)
  /// @param minimum            smallest accepted value (excluded when `minimum_exclusive`)
  /// @param maximum            largest accepted value
  /// @param minimum_exclusive  accept only values greater than `minimum`
  RangedValue(T* store, Wide minimum, Wide maximum, bool minimum_exclusive)
      : boost::program_options::typed_value<T>(store),
        minimum_(minimum),
        maximum_(maximum),
        minimum_exclusive_(minimum_exclusive) {}

  /// @brief boost's parsing hook: reads the token as a Wide number and checks it before storing it as T.
  /// @param value_store  receives the value
  /// @param tokens       the option's one token
  void xparse(boost::any& value_store, const std::vector<std::string>& tokens) const override {
    namespace po = boost::program_options;
    const std::string& text = po::validators::get_single_string(tokens);
    Wide value{};
    bool ok;
    if constexpr (std::is_integral_v<T>)
      ok = detail::parseInteger(text, value);
    else
      ok = detail::parseReal(text, value);
    const bool below = minimum_exclusive_ ? !(value > minimum_) : value < minimum_;
    if (!ok || below || value > maximum_) {
      // %canonical_option% becomes "--k" when boost adds the option's name.
      throw po::error_with_option_name("%canonical_option% must be " +
                                       detail::describeRange(std::is_integral_v<T> && !ok,
                                                             static_cast<double>(minimum_),
                                                             static_cast<double>(maximum_), minimum_exclusive_) +
                                       " (got " + text + ")");
    }
    value_store = static_cast<T>(value);
  }

 private:
  Wide minimum_;
  Wide maximum_;
  bool minimum_exclusive_;
};

/// @brief A numeric option accepting minimum <= value <= maximum (see RangedValue).
/// @param store    where the value goes, as po::value(&variable) does
/// @param minimum  smallest accepted value
/// @param maximum  largest accepted value; by default the largest the type (or long long) holds
template <typename T>
RangedValue<T>* rangedValue(T* store, T minimum, T maximum = std::numeric_limits<T>::max()) {
  if constexpr (std::is_integral_v<T>) {
    // Integers are checked as long long: a larger unsigned maximum means "no upper bound".
    constexpr auto top = static_cast<unsigned long long>(std::numeric_limits<long long>::max());
    const long long bounded =
        static_cast<unsigned long long>(maximum) > top ? static_cast<long long>(top) : static_cast<long long>(maximum);
    return new RangedValue<T>(store, static_cast<long long>(minimum), bounded, false);
  } else {
    return new RangedValue<T>(store, static_cast<double>(minimum), static_cast<double>(maximum), false);
  }
}

/// @brief A floating-point option accepting 0 < value <= maximum (see RangedValue).
/// @param store    where the value goes
/// @param maximum  largest accepted value
inline RangedValue<double>* positiveValue(double* store, double maximum = std::numeric_limits<double>::max()) {
  return new RangedValue<double>(store, 0.0, maximum, true);
}

/// An option naming one value of an enum, read by the library's own parser (parseNamedValue underneath), so the
/// names and the message listing them exist once: anything else is the command-line error (exit 2 through
/// runTool) "--<option>: unknown <what> '<name>' (expected a, b or c)". The name is checked while it is parsed
/// and stored as the enum when the options are notified (boost's typed_value<Enum> would need operator>>).
class NamedValue : public boost::program_options::typed_value<std::string> {
 public:
  /// @brief Use namedValue() rather than this.
  /// @param check calls the library's parser on a name, which throws std::invalid_argument for a wrong one
  explicit NamedValue(std::function<void(const std::string&)> check)
      : boost::program_options::typed_value<std::string>(nullptr), check_(std::move(check)) {}

  /// @brief boost's parsing hook: accepts the token only if the library's parser does.
  /// @param value_store receives the name
  /// @param tokens      the option's one token
  void xparse(boost::any& value_store, const std::vector<std::string>& tokens) const override;

 private:
  std::function<void(const std::string&)> check_;
};

/// @brief An option storing an enum value read by name; its default, shown in --help, is `*store`'s name.
/// @param store   the variable holding the value, and its default
/// @param parse   the library's parser of the names (e.g. frontend::parsePnpMethod)
/// @param name_of the name of a value (e.g. frontend::toString)
template <typename T, typename Parse, typename NameOf>
NamedValue* namedValue(T* store, Parse parse, NameOf name_of) {
  auto* value = new NamedValue([parse](const std::string& name) { parse(name); });
  value->default_value(name_of(*store));
  value->notifier([store, parse](const std::string& name) { *store = parse(name); });
  return value;
}

/// One line on stderr, rewritten in place: "label  12/40  (30%)  eta 5 s".
/// Prints plain lines instead when stderr is not a terminal (CI logs).
class Progress {
 public:
  Progress(std::string label, std::size_t total);
  void step(const std::string& detail = {});
  void finish();

 private:
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool terminal_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_print_;
};

/// A JSON object written in insertion order; values are numbers, bools,
/// strings, matrices (as arrays of rows) or other objects.
class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, int value);
  JsonObject& add(const std::string& key, std::size_t value);
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  JsonObject& add(const std::string& key, const Eigen::MatrixXd& value);
  /// A vector as one flat array.
  JsonObject& add(const std::string& key, const Eigen::Vector3d& value);
  JsonObject& add(const std::string& key, const JsonObject& value);
  /// Single line, no trailing newline.
  std::string str() const;

 private:
  std::vector<std::pair<std::string, std::string>> members_;
};

/// Writes a text file atomically (temporary file, then rename).
void writeTextFile(const std::string& path, const std::string& content);

/// @brief Refuses, as a bad command line (boost::program_options::error), any option of `group` given on the
/// command line (defaults do not count): for options that the run's other choices would silently ignore.
/// @param vm the parsed command line
/// @param group the options that do not apply
/// @param why the end of the error, after "--NAME " (e.g. "applies to the synthetic sequence, not to --dataset")
void refuseOptionsGiven(const boost::program_options::variables_map& vm,
                        const boost::program_options::options_description& group, const std::string& why);

/// @brief Refuses the options the chosen frame source would ignore (a bad command line): with --dataset, any of
/// the synthetic sequence's options; without it, --camera (the synthetic sequence has its own camera).
/// @param vm the parsed command line
/// @param dataset whether --dataset was given
/// @param synthetic_options the group holding the synthetic sequence's options
void requireOptionsOfTheSource(const boost::program_options::variables_map& vm, bool dataset,
                               const boost::program_options::options_description& synthetic_options);

/// @brief Inside a catch block: rethrows the exception being handled, adding "(--overwrite replaces it)" to an
/// io::FolderNotEmptyError (io::AtomicFolder's refusal of a non-empty folder) when --overwrite was not given.
/// @param overwrite the --overwrite switch
[[noreturn]] void rethrowWithOverwriteHint(bool overwrite);

/// @brief A tool's --out folder, opened before the long work so that a refused folder costs nothing: outputs go
/// into the returned folder's path() and appear together at publish(); a run that fails or is interrupted
/// publishes nothing. A non-empty folder is refused (std::runtime_error naming it and --overwrite) unless
/// `overwrite`, which replaces it whole, so no file of an earlier run is left beside the new ones.
/// @param out_dir the --out option's value
/// @param overwrite the --overwrite switch
io::AtomicFolder openOutputFolder(const std::string& out_dir, bool overwrite);

/// @brief Refuses, as a bad command line (boost::program_options::error, exit 2), an output file option whose
/// folder does not exist, before any work is done (a picture asked for is not silently left out at the end).
/// @param path the option's value (a file; empty: not asked for, nothing checked)
/// @param option the option's name, e.g. "--plot"
void requireOutputFolderOf(const std::string& path, const std::string& option);

/// @brief A data file that ships with the tools (the default vocabulary): next to the running executable (the
/// build tree), else in <prefix>/share/weighted_icp/ beside its bin/ (the install tree).
/// @param name the file's name
/// @return its path, or empty when neither exists
std::string findToolDataFile(const std::string& name);

/// @brief --odometry-information's names (wicp_rgbd_slam, wicp_merge): the pose graph's odometry edges with
/// information from tracking ("tracking") or from the fixed noise model ("model").
/// @param from_tracking the option's value
std::string odometryInformationName(bool from_tracking);
/// @brief Parses --odometry-information's value; any other name throws, listing the accepted ones.
/// @param name "tracking" or "model"
bool parseOdometryInformation(const std::string& name);

}  // namespace weighted_icp::tools
