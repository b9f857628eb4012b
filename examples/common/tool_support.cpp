#include "tool_support.h"

#include <algorithm>
#include <boost/program_options/errors.hpp>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include "weighted_icp/core/named_values.h"
#include "weighted_icp/io/atomic_file.h"

namespace weighted_icp::tools {

int runTool(const std::string& tool, const std::function<int()>& body) {
  try {
    return body();
  } catch (const boost::program_options::error& e) {
    std::cerr << tool << ": error: " << e.what() << " (see " << tool << " --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << '\n';
    return 1;
  }
}

bool parseCommandLine(int argc, const char* const argv[], const boost::program_options::options_description& options,
                      boost::program_options::variables_map& vm,
                      const boost::program_options::positional_options_description* positional) {
  namespace po = boost::program_options;
  po::command_line_parser parser(argc, argv);
  parser.options(options);
  if (positional) parser.positional(*positional);
  po::store(parser.run(), vm);
  if (vm.count("help")) {
    std::cout << options << '\n';
    return false;
  }
  po::notify(vm);
  return true;
}

namespace detail {

bool parseInteger(const std::string& text, long long& value) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;  // from_chars takes '-' only
  const auto [end, error] = std::from_chars(first, last, value);
  return error == std::errc() && end == last && first != last;
}

bool parseReal(const std::string& text, double& value) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno == 0 && std::isfinite(value);
}

std::string describeRange(bool integer, double minimum, double maximum, bool minimum_exclusive) {
  const auto shown = [](double v) {
    std::ostringstream out;
    out << std::setprecision(15) << v;
    return out.str();
  };
  const std::string kind = integer ? "an integer " : "";
  const bool unbounded = maximum >= static_cast<double>(std::numeric_limits<long long>::max());
  if (minimum_exclusive)
    return kind + "greater than " + shown(minimum) + (unbounded ? "" : " and at most " + shown(maximum));
  if (unbounded) return kind + "at least " + shown(minimum);
  return kind + "between " + shown(minimum) + " and " + shown(maximum);
}

}  // namespace detail

void NamedValue::xparse(boost::any& value_store, const std::vector<std::string>& tokens) const {
  namespace po = boost::program_options;
  const std::string& name = po::validators::get_single_string(tokens);
  try {
    check_(name);
  } catch (const std::invalid_argument& e) {
    throw po::error_with_option_name(std::string("%canonical_option%: ") + e.what());
  }
  value_store = name;
}

void throwOutOfRange(const std::string& option, const std::string& value, long long minimum, long long maximum) {
  throw boost::program_options::error(
      "--" + option + " must be " +
      detail::describeRange(false, static_cast<double>(minimum), static_cast<double>(maximum), false) + " (got " +
      value + ")");
}

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      terminal_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

void Progress::step(const std::string& detail) {
  ++done_;
  const auto now = std::chrono::steady_clock::now();
  // In a log, one line per step would drown it: print every 10 % or so.
  const bool milestone = total_ < 10 || done_ % (total_ / 10) == 0 || done_ == total_;
  if (!terminal_ && !milestone) return;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double eta = done_ > 0 ? elapsed / done_ * (total_ - done_) : 0.0;
  std::ostringstream line;
  line << label_ << "  " << done_ << '/' << total_ << "  (" << (100 * done_ / std::max<std::size_t>(total_, 1))
       << "%)  eta " << std::fixed << std::setprecision(0) << eta << " s";
  if (!detail.empty()) line << "  " << detail;
  if (terminal_)
    std::cerr << '\r' << line.str() << "\033[K" << std::flush;
  else
    std::cerr << line.str() << '\n';
  last_print_ = now;
}

void Progress::finish() {
  if (terminal_) std::cerr << '\n';
}

namespace {
std::string number(double value) {
  if (!std::isfinite(value)) return "null";  // JSON has no NaN or infinity
  std::ostringstream out;
  out << std::setprecision(std::numeric_limits<double>::max_digits10) << value;
  return out.str();
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}
}  // namespace

JsonObject& JsonObject::add(const std::string& key, double value) {
  members_.emplace_back(key, number(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, int value) {
  members_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, std::size_t value) {
  members_.emplace_back(key, std::to_string(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, bool value) {
  members_.emplace_back(key, value ? "true" : "false");
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  members_.emplace_back(key, quoted(value));
  return *this;
}
JsonObject& JsonObject::add(const std::string& key, const Eigen::MatrixXd& value) {
  std::string rows = "[";
  for (Eigen::Index r = 0; r < value.rows(); ++r) {
    rows += r ? ",[" : "[";
    for (Eigen::Index c = 0; c < value.cols(); ++c) rows += (c ? "," : "") + number(value(r, c));
    rows += "]";
  }
  members_.emplace_back(key, rows + "]");
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const Eigen::Vector3d& value) {
  members_.emplace_back(key, "[" + number(value.x()) + "," + number(value.y()) + "," + number(value.z()) + "]");
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const JsonObject& value) {
  members_.emplace_back(key, value.str());
  return *this;
}

std::string JsonObject::str() const {
  std::string out = "{";
  for (std::size_t i = 0; i < members_.size(); ++i)
    out += (i ? "," : "") + quoted(members_[i].first) + ":" + members_[i].second;
  return out + "}";
}

void writeTextFile(const std::string& path, const std::string& content) {
  io::writeAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary);
    if (!out) throw std::runtime_error("cannot create " + temporary);
    out << content;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path);
  });
}

void requireOutputFolderOf(const std::string& path, const std::string& option) {
  if (path.empty()) return;
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder))
    throw boost::program_options::error(option + " " + path + ": no folder " + folder.string() + " to write it in");
}

void refuseOptionsGiven(const boost::program_options::variables_map& vm,
                        const boost::program_options::options_description& group, const std::string& why) {
  for (const auto& option : group.options()) {
    const std::string& name = option->long_name();
    if (vm.count(name) && !vm[name].defaulted()) throw boost::program_options::error("--" + name + " " + why);
  }
}

void requireOptionsOfTheSource(const boost::program_options::variables_map& vm, bool dataset,
                               const boost::program_options::options_description& synthetic_options) {
  if (dataset)
    refuseOptionsGiven(vm, synthetic_options, "applies to the synthetic sequence, not to --dataset");
  else if (vm.count("camera"))
    throw boost::program_options::error(
        "--camera applies to --dataset only: the synthetic sequence has its own camera");
}

void rethrowWithOverwriteHint(bool overwrite) {
  try {
    throw;
  } catch (const io::FolderNotEmptyError& e) {
    if (!overwrite) throw std::runtime_error(std::string(e.what()) + " (--overwrite replaces it)");
    throw;
  }
}

io::AtomicFolder openOutputFolder(const std::string& out_dir, bool overwrite) {
  try {
    return io::AtomicFolder(out_dir, overwrite);
  } catch (...) {
    rethrowWithOverwriteHint(overwrite);
  }
}

std::string findToolDataFile(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code error;
  // The executable's own folder, whatever the working directory: Linux names it in /proc.
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) return {};
  const fs::path bin = self.parent_path();
  for (const fs::path& candidate : {bin / name, bin.parent_path() / "share" / "weighted_icp" / name})
    if (fs::is_regular_file(candidate, error)) return candidate.string();
  return {};
}

std::string odometryInformationName(bool from_tracking) { return from_tracking ? "tracking" : "model"; }

bool parseOdometryInformation(const std::string& name) {
  return parseNamedValue(name, {true, false}, odometryInformationName, "odometry information");
}

}  // namespace weighted_icp::tools
