#pragma once
// Shared by the mapping tests: keyframes of synthetic sequences with true poses
// (a loop, optionally with repeated texture) and a vocabulary trained on a
// different sequence than the one it is tested on.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "weighted_icp/mapping/binary_vocabulary.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/posed_keyframe_builder.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace weighted_icp::testing {

/// Keyframes every `every` frames of a synthetic sequence, at their true poses.
struct SyntheticKeyframes {
  PinholeCamera camera;
  mapping::KeyframeSnapshot snapshot;
};

/// The given frames of a short loop (the camera goes once round in `frames_per_loop` frames) as keyframes, in
/// the default room or one stretched by `room_scale`.
inline SyntheticKeyframes syntheticKeyframes(std::uint64_t seed, bool repeated_texture, double frames_per_loop,
                                             const std::vector<std::size_t>& frames, double room_scale = 1.0) {
  simulation::SyntheticRgbdOptions options;
  options.room_scale = room_scale;
  options.seed = seed;
  options.frames = frames.empty() ? 1 : frames.back() + 1;
  options.frames_per_loop = frames_per_loop;
  options.repeated_texture = repeated_texture;
  const simulation::SyntheticRgbdSequence sequence(options);
  mapping::PosedKeyframeBuilder builder(options.camera);
  for (std::size_t i : frames) {
    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    builder.add(frame.rgbd, i, frame.camera_to_world);
  }
  return {options.camera, mapping::KeyframeSnapshot::of(builder.map())};
}

/// Every `every`-th frame of the first `frames`.
inline std::vector<std::size_t> everyNth(std::size_t frames, std::size_t every, std::size_t first = 0) {
  std::vector<std::size_t> result;
  for (std::size_t i = first; i < frames; i += every) result.push_back(i);
  return result;
}

/// The descriptors of every keyframe, one matrix per keyframe (what a vocabulary is trained on).
inline std::vector<cv::Mat> keyframeDescriptors(const mapping::KeyframeSnapshot& snapshot) {
  std::vector<cv::Mat> images;
  for (const auto& [id, keyframe] : snapshot.keyframes) images.push_back(keyframe.descriptors);
  return images;
}

/// A vocabulary trained on a synthetic sequence of seed 1001 (its own textures), never on the tested ones.
inline mapping::BinaryVocabulary::ConstPtr trainedVocabulary() {
  static const auto vocabulary = [] {
    const SyntheticKeyframes training = syntheticKeyframes(1001, false, 240.0, everyNth(240, 20));
    mapping::VocabularyTrainingOptions options;
    options.branching = 8;
    options.depth = 4;
    return std::make_shared<const mapping::BinaryVocabulary>(
        mapping::BinaryVocabulary::train(keyframeDescriptors(training.snapshot), options));
  }();
  return vocabulary;
}

}  // namespace weighted_icp::testing
