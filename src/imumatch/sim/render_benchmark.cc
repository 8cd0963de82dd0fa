// Speed of the synthetic world: scene construction (procedural textures) and ray-cast rendering
// of a 640x480 RGB-D frame. The 1-thread, unfiltered render is the baseline for the ratios.
#include <benchmark/benchmark.h>

#include "imumatch/camera/pinhole_camera.h"
#include "imumatch/sim/motions.h"
#include "imumatch/sim/renderer.h"
#include "imumatch/sim/scene.h"

namespace imumatch {
namespace {

const Scene& SharedScene() {
  static const Scene scene;
  return scene;
}

void BM_SceneConstruction(benchmark::State& state) {
  for (auto _ : state) {
    Scene scene;
    benchmark::DoNotOptimize(scene.surfaces().size());
  }
}
BENCHMARK(BM_SceneConstruction)->Unit(benchmark::kMillisecond)->Iterations(2);

// Arguments: threads, texture filtering (0/1), edge supersampling, lens (0: the Kinect-like
// pinhole camera; 1: the TUM fr1 calibration with its lens; 2: the same without the lens).
void BM_RenderView(benchmark::State& state) {
  const Scene& scene = SharedScene();
  PinholeCamera camera = PinholeCamera::KinectDefault();
  if (state.range(3) != 0) camera = PinholeCamera::TumFreiburg1();
  if (state.range(3) == 2) camera.distortion = {0, 0, 0, 0, 0};
  const auto motion = MakeMotion("walk", MotionOptions());
  RenderOptions options;
  options.num_threads = static_cast<int>(state.range(0));
  options.filter_textures = state.range(1) != 0;
  options.edge_supersampling = static_cast<int>(state.range(2));
  const Rigid3d body_from_cam = SyntheticCamFromImu().Inverse();
  double t = 0.0;
  for (auto _ : state) {
    const RenderedView view =
        RenderView(scene, camera, motion->WorldFromBody(t) * body_from_cam, options);
    benchmark::DoNotOptimize(view.rgb.data);
    t = t + 0.1 > motion->EndTime() ? 0.0 : t + 0.1;
  }
  state.counters["pixels/s"] = benchmark::Counter(static_cast<double>(camera.width * camera.height),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RenderView)
    ->Args({1, 0, 1, 0})  // baseline: 1 thread, no prefiltering, no edge supersampling
    ->Args({1, 1, 1, 0})
    ->Args({1, 1, 3, 0})
    ->Args({2, 1, 3, 0})  // the default
    ->Args({2, 1, 3, 1})  // through the TUM fr1 lens
    ->Args({2, 1, 3, 2})  // the same intrinsics without it
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace imumatch

BENCHMARK_MAIN();
