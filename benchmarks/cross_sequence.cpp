// The cross-sequence table of issue #11: the front end (default, and each
// quality-gate mode) next to cv::rgbd::RgbdOdometry on fr1 head, fr3 head, the
// synthetic sequence and variants of each (JPEG colour, depth in millimetres,
// another focal length, unregistered depth, motion blur, low light, bursts of
// bad frames, and "kinect": JPEG + mm depth + focal 585 together, the held-out
// Kinect's format). Variants are written into --scratch (never into the source
// tree) and read back as TUM folders with their camera.yaml, as a user would.
// Prints Markdown: ATE RMSE with frames without a pose, tracking times, and how
// often ours has the lower ATE over resamples of the poses (metrics::compareAte).
//
//   wicp_benchmark_cross_sequence --scratch DIR [--data DIR] [--max-frames N]
//                                 [--synthetic-frames N] [--sequences LIST] [--variants LIST] [--runs LIST]
//                                 [--resolution-scale S] [--depth-resolution-scale S] [--crop-aspect A]
//                                 [--exposure-stops S] [--frame-step N]
//                                 [--trajectories DIR]

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "rgbd_odometry_runs.h"
#include "weighted_icp/frontend/slam/frontend_choices.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/simulation/sequence_variants.h"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace weighted_icp;
using benchmarks::Run;
using benchmarks::Sequence;

namespace {

/// A base sequence: a TUM folder with its camera, or the synthetic one.
struct Base {
  std::string name;
  simulation::VariantSource source;
};

/// A tracker configuration: a column of the table.
struct Tracker {
  std::string name;
  bool opencv = false;
  frontend::RgbdSlamOptions options;
};

std::vector<Tracker> trackers(const std::string& list) {
  std::vector<Tracker> all;
  std::stringstream names(list);
  std::string name;
  while (std::getline(names, name, ',')) {
    Tracker tracker{name, name == "opencv", {}};
    auto& quality = tracker.options.frontend.quality;
    if (name == "relative-brisque") {
      quality.measure = frontend::QualityMeasure::Brisque;
    } else if (name == "absolute") {
      quality.mode = frontend::QualityGateMode::Absolute;
    } else if (name == "paper") {
      quality.mode = frontend::QualityGateMode::PaperEveryFrame;
    } else if (name == "no-gate") {
      tracker.options.frontend.quality_gate = false;
    } else if (name != "default" && name != "opencv") {
      throw po::error("--runs: unknown run '" + name +
                      "' (expected default, relative-brisque, absolute, paper, no-gate, opencv)");
    }
    all.push_back(tracker);
  }
  return all;
}

/// "kinect" is the held-out Kinect's format; other names are sequence_variants.h kinds; "a+b" combines them
/// (e.g. kinect+low-light).
std::vector<simulation::VariantKind> kindsOf(const std::string& variant) {
  std::string kinds;
  std::stringstream parts(variant);
  for (std::string part; std::getline(parts, part, '+');)
    kinds += (kinds.empty() ? "" : ",") + (part == "kinect" ? std::string("jpeg,mm-depth,focal") : part);
  return simulation::parseVariantKinds(kinds);
}

Sequence load(const fs::path& dir, const std::string& name) {
  const io::TumSequence tum = io::TumSequence::open(dir.string());
  Sequence sequence{name, io::loadCamera((dir / "camera.yaml").string()), {}, tum.groundTruth()};
  for (std::size_t i = 0; i < tum.size(); ++i) sequence.frames.push_back(tum.loadFrame(i, sequence.camera));
  return sequence;
}

/// The base itself (variant "original") or a variant, written into the scratch folder and read back.
/// @param parameters the kinds' parameters (--resolution-scale, --depth-resolution-scale); its kinds are ignored
Sequence prepare(const Base& base, const std::string& variant, const fs::path& scratch,
                 const simulation::SequenceVariantOptions& parameters) {
  const fs::path dir = scratch / (base.name + "_" + variant);
  simulation::SequenceVariantOptions options = parameters;
  // "original" rewrites the frames unchanged (PNG, same camera): the same path as every variant.
  options.kinds = variant == "original" ? std::vector<simulation::VariantKind>{} : kindsOf(variant);
  if (options.kinds.empty()) {
    options.kinds = {simulation::VariantKind::MillimetreDepth};
    options.depth_factor = base.source.camera.depth_factor;
  }
  simulation::writeSequenceVariant(base.source, options, dir.string(), true);
  return load(dir, base.name + (variant == "original" ? "" : ", " + variant));
}

std::string cell(const Run& run, std::size_t frames) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(2);
  if (std::isnan(run.ate_rmse_m))
    text << "–";
  else
    text << run.ate_rmse_m * 100;
  text << " (" << frames - run.tracked << ")";
  return text.str();
}

/// How often the default's ATE is the lower one over resamples of the poses both have (metrics::compareAte):
/// near 50 %, a difference the sequence cannot show.
std::string versus(const Trajectory& truth, const std::optional<Trajectory>& ours,
                   const std::optional<Trajectory>& opencv) {
  if (!ours || !opencv) return "–";
  try {
    std::ostringstream text;
    text << std::fixed << std::setprecision(0)
         << 100.0 * metrics::compareAte(truth, *ours, *opencv).first_lower_fraction << " %";
    return text.str();
  } catch (const std::runtime_error&) {
    return "–";  // fewer than 3 poses in common
  }
}

void requireOutsideSourceTree(const std::string& option, const fs::path& folder) {
  const std::string source = fs::weakly_canonical(WEIGHTED_ICP_SOURCE_DIR).string() + "/";
  const std::string target = fs::weakly_canonical(fs::absolute(folder)).string() + "/";
  if (target.rfind(source, 0) == 0)
    throw po::error("--" + option + " " + folder.string() + " is inside the source tree " + source +
                    "; what is made of shared data must not be written into the repository");
}

/// "fr1_head, jpeg" -> "fr1_head_jpeg": a row's name as part of a file name.
std::string fileStem(const std::string& row) {
  std::string stem;
  for (const char c : row)
    if (c != ' ') stem += c == ',' ? '_' : c;
  return stem;
}

/// Everything the command line sets.
struct CrossSequenceCommand {
  std::string data = WEIGHTED_ICP_DATA_DIR, scratch, trajectories;
  std::string variants = "jpeg,mm-depth,focal,unregistered,blur,low-light,burst,kinect";
  std::string runs = "default,relative-brisque,absolute,paper,no-gate,opencv";
  std::string sequences = "fr1_head,fr3_head,synthetic";
  std::size_t max_frames = 0, synthetic_frames = 150;
  std::vector<std::string> choices;  // --frontend-option KEY=VALUE
  simulation::SequenceVariantOptions parameters;
};

/// Parses and checks the command line into `c`; false when only --help was asked for.
bool parseCommand(int argc, char** argv, CrossSequenceCommand& c) {
  simulation::SequenceVariantOptions& p = c.parameters;
  po::options_description description("wicp_benchmark_cross_sequence options");
  // clang-format off
  description.add_options()
      ("help,h", "print this help")
      ("scratch", po::value(&c.scratch)->required(), "folder for the variants (outside the source tree)")
      ("data", po::value(&c.data)->default_value(c.data), "folder with tum_fr1_xyz_head and tum_fr3_teddy_head")
      ("max-frames", po::value(&c.max_frames)->default_value(c.max_frames), "frames per TUM sequence (0 = all)")
      ("synthetic-frames", po::value(&c.synthetic_frames)->default_value(c.synthetic_frames), "synthetic sequence length (0 = none)")
      ("sequences", po::value(&c.sequences)->default_value(c.sequences), "comma-separated: fr1_head, fr3_head, synthetic")
      ("variants", po::value(&c.variants)->default_value(c.variants), "comma-separated variants (kinds of wicp_make_variant, or kinect; a+b combines two, e.g. kinect+blur)")
      ("runs", po::value(&c.runs)->default_value(c.runs), "comma-separated: default, relative-brisque, absolute, paper, no-gate, opencv")
      ("resolution-scale", po::value(&p.resolution_scale)->default_value(p.resolution_scale), "variant resolution: new width / old (0.25-4)")
      ("depth-resolution-scale", po::value(&p.depth_resolution_scale)->default_value(p.depth_resolution_scale), "variant depth-resolution: depth width / colour width (0.25-4)")
      ("crop-aspect", po::value(&p.crop_aspect)->default_value(p.crop_aspect), "variant crop: width / height kept (1-4; 1.7778: 16:9)")
      ("exposure-stops", po::value(&p.exposure_stops)->default_value(p.exposure_stops), "variant exposure: most stops a frame's light is off (0-4)")
      ("frame-step", po::value(&p.frame_step)->default_value(p.frame_step), "variant frame-step: keep every N-th frame (1-30)")
      ("frontend-option", po::value(&c.choices)->composing(),
       "KEY=VALUE, repeatable: a front-end choice by wicp_rgbd_slam's option name (pnp=iterative, "
       "descriptor=modified-brief, dense-odometry=prior, ...), applied to every run but opencv")
      ("trajectories", po::value(&c.trajectories),
       "also write every run's trajectory (TUM format) into this folder as SEQUENCE_RUN.txt, with the "
       "ground truth as SEQUENCE_groundtruth.txt, to see where one loses (wicp_evaluate --plot)");
  // clang-format on
  po::variables_map vm;
  po::store(po::parse_command_line(argc, argv, description), vm);
  if (vm.count("help")) {
    std::cout << description << '\n';
    return false;
  }
  po::notify(vm);
  requireOutsideSourceTree("scratch", c.scratch);
  if (!c.trajectories.empty()) requireOutsideSourceTree("trajectories", c.trajectories);
  return true;
}

/// The table's columns (--runs), each front-end run with the --frontend-option choices.
std::vector<Tracker> columnsOf(const CrossSequenceCommand& c) {
  std::vector<Tracker> columns = trackers(c.runs);
  for (const std::string& choice : c.choices) {
    const std::size_t equals = choice.find('=');
    if (equals == std::string::npos) throw po::error("--frontend-option " + choice + ": expected KEY=VALUE");
    for (Tracker& column : columns) {
      try {
        frontend::setFrontendChoice(column.options.frontend, choice.substr(0, equals), choice.substr(equals + 1));
      } catch (const std::invalid_argument& e) {
        throw po::error(std::string("--frontend-option: ") + e.what());
      }
    }
  }
  return columns;
}

/// "original" and the --variants, each checked before any run.
std::vector<std::string> variantNames(const std::string& variants) {
  std::vector<std::string> names{"original"};
  std::stringstream list(variants);
  for (std::string name; std::getline(list, name, ',');) {
    kindsOf(name);  // an unknown name fails before any run
    names.push_back(name);
  }
  return names;
}

/// The --sequences found: the TUM heads in --data (a missing one is skipped, saying so) and the synthetic sequence.
std::vector<Base> basesOf(const CrossSequenceCommand& c) {
  std::vector<Base> bases;
  for (const auto& [folder, freiburg] :
       {std::pair<const char*, int>{"tum_fr1_xyz_head", 1}, {"tum_fr3_teddy_head", 3}}) {
    const std::string dir = c.data + "/" + folder;
    if (!fs::exists(dir)) {
      std::cerr << "skipping " << dir << ": not found\n";
      continue;
    }
    const std::string name = folder == std::string("tum_fr1_xyz_head") ? "fr1_head" : "fr3_head";
    if (c.sequences.find(name) == std::string::npos) continue;
    Base base{name, simulation::tumVariantSource(dir, tumCamera(freiburg))};
    if (c.max_frames) base.source.size = std::min(base.source.size, c.max_frames);
    bases.push_back(base);
  }
  if (c.synthetic_frames > 0 && c.sequences.find("synthetic") != std::string::npos) {
    simulation::SyntheticRgbdOptions synthetic;
    synthetic.frames = c.synthetic_frames;
    bases.push_back({"synthetic", simulation::syntheticVariantSource(synthetic)});
  }
  return bases;
}

/// The Markdown table's header.
void printHeader(const std::vector<Tracker>& columns) {
  std::cout << "ATE RMSE in cm (frames without a pose)\n\n| sequence | frames |";
  for (const Tracker& tracker : columns) std::cout << ' ' << tracker.name << " |";
  std::cout << " median / p90 ms, default | median / p90 ms, opencv | default lower than opencv |\n|---|---|";
  for (std::size_t c = 0; c < columns.size() + 3; ++c) std::cout << "---|";
  std::cout << std::endl;
}

/// One row: every column run on one sequence, its trajectories written when --trajectories asks.
void printRow(const Sequence& sequence, const std::vector<Tracker>& columns, const std::string& trajectories) {
  std::cout << "| " << sequence.name << " | " << sequence.frames.size() << " |";
  std::string timing[2] = {"–", "–"};
  std::optional<Trajectory> ours, opencv;
  if (!trajectories.empty())
    io::writeTrajectory(sequence.truth, trajectories + "/" + fileStem(sequence.name) + "_groundtruth.txt");
  for (const Tracker& tracker : columns) {
    const Run run =
        tracker.opencv ? benchmarks::runOpenCvOdometry(sequence) : benchmarks::runFrontend(sequence, tracker.options);
    std::cout << ' ' << cell(run, sequence.frames.size()) << " |" << std::flush;
    if (!trajectories.empty())
      io::writeTrajectory(run.estimate, trajectories + "/" + fileStem(sequence.name) + "_" + tracker.name + ".txt");
    std::ostringstream ms;
    ms << std::fixed << std::setprecision(1) << run.medianMs() << " / " << run.p90Ms();
    if (tracker.name == "default") {
      timing[0] = ms.str();
      ours = run.estimate;
    }
    if (tracker.opencv) {
      timing[1] = ms.str();
      opencv = run.estimate;
    }
  }
  std::cout << ' ' << timing[0] << " | " << timing[1] << " | " << versus(sequence.truth, ours, opencv) << " |"
            << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    CrossSequenceCommand c;
    if (!parseCommand(argc, argv, c)) return 0;
    const std::vector<Tracker> columns = columnsOf(c);
    const std::vector<std::string> variants = variantNames(c.variants);
    if (!c.trajectories.empty()) fs::create_directories(c.trajectories);
    const std::vector<Base> bases = basesOf(c);
    printHeader(columns);
    for (const Base& base : bases)
      for (const std::string& variant : variants)
        printRow(prepare(base, variant, c.scratch, c.parameters), columns, c.trajectories);
    return 0;
  } catch (const po::error& e) {
    std::cerr << "wicp_benchmark_cross_sequence: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "wicp_benchmark_cross_sequence: error: " << e.what() << '\n';
    return 1;
  }
}
