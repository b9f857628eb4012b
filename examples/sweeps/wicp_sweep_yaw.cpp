// wicp_sweep_yaw: sweeps the yaw (about z) from 0 to 70 deg in steps of 10, in both directions.
// Every sweep is the same tool (sweep.h); this one only chooses its cases.

#include "sweep.h"

int main(int argc, char** argv) {
  using namespace weighted_icp::sweep;
  return runSweepTool("wicp_sweep_yaw", yawSweep(), argc, argv);
}
