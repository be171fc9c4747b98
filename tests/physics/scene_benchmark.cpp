// Fig. 10 of the AMBF paper, on afhub: the time to load N robots into one world
// (parse the files, read the meshes, build the Bullet world), for N from 1 to 16.
// The robots: the project's example arm, RCM arm and gripper in turn (no ../shared
// needed), and the da Vinci ECM from ../shared loaded N times (each a copy with its
// own channels). Run: build/release/bin/scene_benchmark, and
// docs/plot_load_time.py --json FILE to plot (docs/load_time.png). Also N bodies
// at one point, every pair of them overlapping, for N from 1000 to 8000: loading
// must stay linear in N (it was cubic: 8000 took over 100 s).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

const std::string kExamples = AFHUB_EXAMPLE_MODELS "/";
const std::string kEcm = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/robots/blender-ecm.yaml";

void load(benchmark::State& state, const std::vector<std::string>& files) {
  std::size_t bodies = 0;
  for (auto _ : state) {
    Model model = load_adf_files(files);
    Simulation sim(model, 0.001);
    benchmark::DoNotOptimize(sim.step_count());
    bodies = model.bodies.size();
  }
  state.counters["robots"] = static_cast<double>(files.size());
  state.counters["bodies"] = static_cast<double>(bodies);
}

// The example arm, RCM arm and gripper in turn: N robots, copies from the fourth on.
void BM_LoadExampleRobots(benchmark::State& state) {
  const std::vector<std::string> kinds = {kExamples + "arm7.yaml", kExamples + "rcm.yaml",
                                          kExamples + "gripper.yaml"};
  std::vector<std::string> files;
  for (int n = 0; n < state.range(0); ++n) files.push_back(kinds[n % kinds.size()]);
  load(state, files);
}
BENCHMARK(BM_LoadExampleRobots)
    ->ArgName("robots")
    ->DenseRange(1, 8)
    ->Arg(16)
    ->Unit(benchmark::kMillisecond);

// The ECM (closed loops, meshes) N times.
void BM_LoadEcms(benchmark::State& state) {
  if (!afhub::testing::shared_models_present()) {
    state.SkipWithError(afhub::testing::shared_models_missing().c_str());
    return;
  }
  load(state, std::vector<std::string>(static_cast<std::size_t>(state.range(0)), kEcm));
}
BENCHMARK(BM_LoadEcms)->ArgName("robots")->DenseRange(1, 8)->Arg(16)->Unit(benchmark::kMillisecond);

// N passive spheres at the origin: N^2/2 overlapping pairs for the first step to meet.
void BM_LoadOverlappingBodies(benchmark::State& state) {
  const afhub::testing::ModelFolder folder;
  const auto count = static_cast<int>(state.range(0));
  load(state, {folder.write("overlapping.yaml", afhub::testing::passive_spheres_at_origin(count))});
}
BENCHMARK(BM_LoadOverlappingBodies)
    ->ArgName("bodies")
    ->Arg(1000)
    ->Arg(2000)
    ->Arg(4000)
    ->Arg(8000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace afhub::physics

BENCHMARK_MAIN();
