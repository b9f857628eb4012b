// wicp_sweep_xy: sweeps XY offsets: the four quadrants (+-a, +-a) for a in {0.25,0.5,1,1.5,2} m.
// Every sweep is the same tool (sweep.h); this one only chooses its cases.

#include "sweep.h"

int main(int argc, char** argv) {
  using namespace weighted_icp::sweep;
  return runSweepTool("wicp_sweep_xy", xySweep(), argc, argv);
}
