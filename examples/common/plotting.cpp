// The tools' pictures through scripts/plot_results.py: tables in a scratch folder, the script, an atomic rename.
#include "plotting.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <stdexcept>

#include "weighted_icp/io/atomic_file.h"
#include "weighted_icp/io/trajectory.h"

extern char** environ;

namespace weighted_icp::tools {

namespace fs = std::filesystem;

namespace {

/// The script's exit status when matplotlib cannot be imported (scripts/plot_results.py says so too).
constexpr int kNoMatplotlib = 3;

/// A table for the script: a header line, then one line of numbers per row, at round-trip precision.
void writeTable(const fs::path& path, const std::string& header, const std::vector<std::vector<double>>& rows) {
  std::ofstream out(path);
  out << header << '\n' << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) out << (c ? "," : "") << row[c];
    out << '\n';
  }
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

/// A fresh scratch folder for the tables, removed when this goes out of scope.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::string pattern = (fs::temp_directory_path() / "wicp_plot_XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error("cannot create a scratch folder: " + std::string(std::strerror(errno)));
    path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// Runs the script on the tables in `data` and publishes the picture; a warning and false on any failure.
bool draw(const std::string& tool, const std::string& kind, const fs::path& data, const std::string& png,
          const std::string& title) {
  // WEIGHTED_ICP_PLOT_PYTHON picks another interpreter (and lets the tests take matplotlib away).
  const char* chosen = std::getenv("WEIGHTED_ICP_PLOT_PYTHON");
  const std::string python = chosen && *chosen ? chosen : WEIGHTED_ICP_PYTHON;
  const std::string script = WEIGHTED_ICP_PLOT_RESULTS_SCRIPT;
  try {
    if (!fs::exists(python)) throw std::runtime_error(python + " not found (Debian: python3 with python3-matplotlib)");
    if (!fs::exists(script)) throw std::runtime_error(script + " not found (it is in the source tree's scripts/)");
    const fs::path folder = fs::absolute(png).parent_path();
    if (!fs::is_directory(folder)) throw std::runtime_error("the folder " + folder.string() + " does not exist");
    io::writeAtomically(png, [&](const std::string& temporary) {
      runProcess({python, script, kind, "--data", data.string(), "--out", temporary, "--title", title});
    });
    return true;
  } catch (const std::exception& e) {
    std::cerr << tool << ": warning: no plot " << png << ": " << e.what() << '\n';
    return false;
  }
}

}  // namespace

namespace {

/// The last non-empty line of a file (a Python traceback's last line says what went wrong), clipped; "" if none.
std::string lastLineOf(const fs::path& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  const std::size_t start = last.find_first_not_of(" \t");
  last = start == std::string::npos ? std::string() : last.substr(start);
  return last.size() > 200 ? last.substr(0, 200) + "..." : last;
}

}  // namespace

void runProcess(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // The child's stderr goes to a file: on failure its last line is the message, not a whole traceback on ours.
  std::string log = (fs::temp_directory_path() / "wicp_process_XXXXXX").string();
  const int log_fd = ::mkstemp(log.data());
  if (log_fd < 0) throw std::runtime_error("cannot create a log file for " + argv[0] + ": " + std::strerror(errno));
  struct Cleanup {
    int fd;
    std::string path;
    ~Cleanup() {
      ::close(fd);
      ::unlink(path.c_str());
    }
  } cleanup{log_fd, log};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, log_fd, STDERR_FILENO);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(error));
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) throw std::runtime_error("lost " + argv[0] + ": " + std::strerror(errno));
  if (WIFEXITED(status) && WEXITSTATUS(status) == kNoMatplotlib && argv.size() > 1)
    throw std::runtime_error("matplotlib is not installed for " + argv[0] + " (Debian: python3-matplotlib)");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string said = lastLineOf(log);
    throw std::runtime_error(
        (argv.size() > 1 ? argv[1] : argv[0]) + " failed (" +
        (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status)) : std::string("killed by a signal")) +
        ")" + (said.empty() ? std::string() : ": " + said));
  }
}

bool plotTrajectory(const std::string& tool, const Trajectory& groundtruth, const Trajectory& estimate,
                    const Eigen::Isometry3d& alignment, double max_difference, const std::string& png,
                    const std::string& title) {
  try {
    ScratchFolder scratch;
    std::vector<std::vector<double>> truth_rows, pairs;
    for (const auto& [t, pose] : groundtruth)
      truth_rows.push_back({t, pose.translation().x(), pose.translation().y(), pose.translation().z()});
    for (const auto& [g, e] : io::associate(groundtruth, estimate, max_difference)) {
      const Eigen::Vector3d truth = groundtruth[g].pose.translation();
      const Eigen::Vector3d moved = alignment * estimate[e].pose.translation();
      pairs.push_back({estimate[e].timestamp, truth.x(), truth.y(), truth.z(), moved.x(), moved.y(), moved.z(),
                       (moved - truth).norm()});
    }
    writeTable(scratch.path() / "groundtruth.csv", "t,x,y,z", truth_rows);
    writeTable(scratch.path() / "pairs.csv", "t,gt_x,gt_y,gt_z,est_x,est_y,est_z,error", pairs);
    return draw(tool, "trajectory", scratch.path(), png, title);
  } catch (const std::exception& e) {
    std::cerr << tool << ": warning: no plot " << png << ": " << e.what() << '\n';
    return false;
  }
}

bool plotAlignment(const std::string& tool, const std::vector<Eigen::Vector3d>& source,
                   const std::vector<Eigen::Vector3d>& target, const std::vector<double>& target_weights,
                   const Eigen::Matrix4d& transformation, const std::string& png, const std::string& title) {
  try {
    ScratchFolder scratch;
    const Eigen::Isometry3d motion(transformation);
    std::vector<std::vector<double>> source_rows, target_rows;
    for (const Eigen::Vector3d& p : source) {
      const Eigen::Vector3d q = motion * p;
      source_rows.push_back({p.x(), p.y(), p.z(), q.x(), q.y(), q.z()});
    }
    for (std::size_t i = 0; i < target.size(); ++i)
      target_rows.push_back(
          {target[i].x(), target[i].y(), target[i].z(), i < target_weights.size() ? target_weights[i] : 1.0});
    writeTable(scratch.path() / "source.csv", "x,y,z,aligned_x,aligned_y,aligned_z", source_rows);
    writeTable(scratch.path() / "target.csv", "x,y,z,weight", target_rows);
    return draw(tool, "alignment", scratch.path(), png, title);
  } catch (const std::exception& e) {
    std::cerr << tool << ": warning: no plot " << png << ": " << e.what() << '\n';
    return false;
  }
}

bool plotAlignment(const std::string& tool, const LandmarkMap& source, const LandmarkMap& target,
                   const WeightFunction& weight, const Eigen::Matrix4d& transformation, const std::string& png,
                   const std::string& title) {
  std::vector<double> weights;
  try {
    weights = computeWeights(target, weight);
  } catch (const std::exception& e) {
    std::cerr << tool << ": warning: no plot " << png << ": " << e.what() << '\n';
    return false;
  }
  const auto positions = [](const LandmarkMap& map) {
    std::vector<Eigen::Vector3d> out;
    for (const Landmark& landmark : map.landmarks) out.push_back(landmark.position);
    return out;
  };
  return plotAlignment(tool, positions(source), positions(target), weights, transformation, png, title);
}

bool plotPaths(const std::string& tool, const std::vector<Trajectory>& paths, const std::vector<std::string>& names,
               const std::vector<PlottedLoop>& loops, const std::string& png, const std::string& title) {
  try {
    if (names.size() != paths.size()) throw std::invalid_argument("one name per path is needed");
    ScratchFolder scratch;
    std::vector<std::vector<double>> path_rows, loop_rows;
    for (std::size_t s = 0; s < paths.size(); ++s)
      for (const auto& [t, pose] : paths[s]) {
        const Eigen::Vector3d p = pose.translation();
        path_rows.push_back({static_cast<double>(s), t, p.x(), p.y(), p.z()});
      }
    for (const PlottedLoop& loop : loops)
      loop_rows.push_back({loop.query.x(), loop.query.y(), loop.query.z(), loop.match.x(), loop.match.y(),
                           loop.match.z(), loop.used ? 1.0 : 0.0});
    writeTable(scratch.path() / "paths.csv", "path,t,x,y,z", path_rows);
    writeTable(scratch.path() / "loops.csv", "qx,qy,qz,mx,my,mz,used", loop_rows);
    std::ofstream labels(scratch.path() / "names.txt");
    for (const std::string& name : names) labels << name << '\n';
    if (!labels) throw std::runtime_error("cannot write the paths' names");
    labels.close();
    return draw(tool, "paths", scratch.path(), png, title);
  } catch (const std::exception& e) {
    std::cerr << tool << ": warning: no plot " << png << ": " << e.what() << '\n';
    return false;
  }
}

}  // namespace weighted_icp::tools
