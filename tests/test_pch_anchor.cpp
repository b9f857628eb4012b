// Compiled only so that weighted_icp_test_pch builds the test programs' shared precompiled header.
