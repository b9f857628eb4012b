#pragma once
// A quality score judged against the sequence's own recent scores (a robust
// z-score: median and MAD of a sliding window), not against an absolute
// threshold: JPEG colour, another sensor or another light shift a whole
// sequence's BRISQUE scores, and a threshold chosen on one sequence then
// refuses good frames of another (issue #11).

#include <cstddef>
#include <deque>
#include <limits>

namespace weighted_icp::frontend {

struct RelativeQualityGateOptions {
  /// Recent scores the median and MAD are taken over. A burst shorter than half
  /// the window cannot move the median; a lasting change (dusk, a new room) is
  /// followed after half a window.
  std::size_t window = 25;
  /// Fewer scores than this and nothing is refused: there is no "usual" yet.
  std::size_t min_history = 5;
  /// Refused above this many robust standard deviations worse than the median.
  double max_z = 3.0;
  /// Floor of the robust standard deviation (score units): on a steady
  /// sequence the MAD is tiny and ordinary jitter would otherwise look extreme.
  double min_spread = 2.0;
  /// Refuse scores far from the median on either side (|z| > max_z), not only
  /// worse ones: for a sharpness measure, where blur lowers it and noise raises it.
  bool two_sided = false;
};

/// @brief One score's verdict and what it was judged against.
struct QualityJudgement {
  double score = std::numeric_limits<double>::quiet_NaN();
  double median = std::numeric_limits<double>::quiet_NaN();  // of the window before this score
  double spread = std::numeric_limits<double>::quiet_NaN();  // 1.4826 MAD, floored by min_spread
  double z = std::numeric_limits<double>::quiet_NaN();       // (score - median) / spread
  bool refused = false;
  /// The score was bad enough but the frame was kept (must_keep, or warm-up).
  bool kept_anyway = false;
};

/// @brief Judges scores (higher is worse, or two-sided) against the recent ones.
class RelativeQualityGate {
 public:
  /// @brief A gate with an empty history.
  /// @param options window, warm-up and threshold; window and min_history are at least 1
  explicit RelativeQualityGate(RelativeQualityGateOptions options = {});

  /// @brief Judges `score` against the window (refused when z > max_z, or
  /// |z| > max_z when two-sided), then adds it to the window (a
  /// refused score too: the window describes the sequence, bad frames included,
  /// and the median is robust to them). A non-finite score is refused (unless
  /// `must_keep`) and not added.
  /// @param score the frame's score, higher is worse
  /// @param must_keep the caller cannot afford to lose this frame: never refused
  QualityJudgement judge(double score, bool must_keep = false);

  /// @brief Scores in the window.
  std::size_t historySize() const { return recent_.size(); }
  /// @brief Forgets the history (a new sequence).
  void reset() { recent_.clear(); }
  const RelativeQualityGateOptions& options() const { return options_; }

 private:
  RelativeQualityGateOptions options_;
  std::deque<double> recent_;
};

}  // namespace weighted_icp::frontend
