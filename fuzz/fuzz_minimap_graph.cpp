// Fuzz target: the mini-map graph's text format (mapping/minimap_graph.h). A graph that loads must save and load
// back to the same nodes and edges, and merge its mini-maps into one map without throwing.
#include <string>

#include "fuzz_support.h"
#include "weighted_icp/mapping/minimap_graph.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string path = fuzz::writeInput("graph.txt", {reinterpret_cast<const char*>(data), size});
  mapping::MiniMapGraph graph;
  if (!fuzz::refusedClearlyOrParsed(path, [&] { graph = mapping::loadMiniMapGraph(path); })) return 0;
  const std::string saved = (fuzz::scratchFolder() / "saved.txt").string();
  mapping::saveMiniMapGraph(graph, saved);
  const mapping::MiniMapGraph reread = mapping::loadMiniMapGraph(saved);
  fuzz::require(reread.nodes().size() == graph.nodes().size() && reread.edges().size() == graph.edges().size(),
                "a graph does not save and load back to the same nodes and edges");
  for (std::size_t i = 0; i < graph.nodes().size(); ++i) {
    const auto &a = graph.nodes()[i], &b = reread.nodes()[i];
    fuzz::require(a.session == b.session && a.anchor_wc.isApprox(b.anchor_wc, 1e-9) &&
                      a.landmarks.landmarks.size() == b.landmarks.landmarks.size() &&
                      a.landmarks.frames.size() == b.landmarks.frames.size(),
                  "a graph's node does not save and load back to itself");
  }
  for (std::size_t i = 0; i < graph.edges().size(); ++i) {
    const auto &a = graph.edges()[i], &b = reread.edges()[i];
    fuzz::require(a.from == b.from && a.to == b.to && a.kind == b.kind && a.strategy == b.strategy &&
                      a.fitness == b.fitness && a.covariance == b.covariance,
                  "a graph's edge does not save and load back to itself");
  }
  graph.mergedMap();
  return 0;
}
