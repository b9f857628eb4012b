// The tools' frame-range lists: parsed, each range checked, the option named in every error.
#include "frame_ranges.h"

#include <algorithm>
#include <charconv>

#include <boost/program_options/errors.hpp>

namespace weighted_icp::tools {

namespace {

FrameId parseFrameId(const std::string& text, const std::string& range, const std::string& option) {
  FrameId id = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (text.empty() || error != std::errc() || end != text.data() + text.size())
    throw boost::program_options::error(option + ": '" + range + "' is not FIRST-LAST with frame ids FIRST <= LAST");
  return id;
}

}  // namespace

std::vector<FrameRange> parseFrameRanges(const std::string& text, const std::string& option) {
  std::vector<FrameRange> ranges;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string range = text.substr(start, comma - start);
    const std::size_t dash = range.find('-');
    const FrameRange parsed{parseFrameId(range.substr(0, dash), range, option),
                            parseFrameId(dash == std::string::npos ? "" : range.substr(dash + 1), range, option)};
    if (parsed.first > parsed.last)
      throw boost::program_options::error(option + ": '" + range + "' is not FIRST-LAST with frame ids FIRST <= LAST");
    ranges.push_back(parsed);
    start = comma + 1;
  }
  return ranges;
}

}  // namespace weighted_icp::tools
