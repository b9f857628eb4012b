// wicp_sweep_k: sweeps the neighbourhood size k over {1,3,5,7,10,15,20} at five displacements.
// Every sweep is the same tool (sweep.h); this one only chooses its cases.

#include "sweep.h"

int main(int argc, char** argv) {
  using namespace weighted_icp::sweep;
  return runSweepTool("wicp_sweep_k", kSweep(), argc, argv);
}
