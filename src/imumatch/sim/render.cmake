# Synthetic world (motions, spline trajectories, scene, renderer, synthetic sequences).
# Included by sim/CMakeLists.txt; appends to the lists it passes to imumatch_add_library/test and
# to SIM_BENCHMARK_SRCS for the sim_benchmark executable.
list(APPEND SIM_SRCS motions.cc spline_trajectory.cc scene.cc renderer.cc synthetic_sequence.cc)
list(APPEND SIM_HDRS motions.h spline_trajectory.h scene.h renderer.h seed_mix.h
     synthetic_sequence.h)
list(APPEND SIM_TEST_SRCS motions_test.cc spline_trajectory_test.cc renderer_test.cc
     synthetic_sequence_test.cc)
list(APPEND SIM_BENCHMARK_SRCS render_benchmark.cc)
