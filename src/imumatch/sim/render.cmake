# Synthetic world (motions, spline trajectories, scene, renderer, synthetic sequences).
# Included by sim/CMakeLists.txt; appends to the lists it passes to imumatch_add_library/test.
list(APPEND SIM_SRCS motions.cc)
list(APPEND SIM_HDRS motions.h)
list(APPEND SIM_TEST_SRCS motions_test.cc)
