// wicp_sweep_xy_yaw: sweeps XY plus yaw: the quadrants (+-0.5 m, +-0.5 m) at yaw -30, -10, 10, 30 deg.
// Every sweep is the same tool (sweep.h); this one only chooses its cases.

#include "sweep.h"

int main(int argc, char** argv) {
  using namespace weighted_icp::sweep;
  return runSweepTool("wicp_sweep_xy_yaw", xyYawSweep(), argc, argv);
}
