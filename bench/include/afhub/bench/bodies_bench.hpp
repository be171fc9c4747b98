// `afhub bench bodies`: issue 30's thousand bodies across processes. `afhub run`
// simulates the generated scene of arms (arms_scene.hpp) in real time, and this
// process commands every body of it each millisecond from one loop, in phase with the
// physics as every controller is by default. Measured from the physics' own step log:
// each step's commands read, Bullet's step and the states published; from its world
// state: the share of commands in time for the next step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/bench/step_log.hpp"
#include "afhub/rt/latency_histogram.hpp"

namespace afhub::bench {

struct BodiesOptions {
  int arms = 125, links = 8;         // 1000 bodies
  double seconds = 20.0;             // measured, after the controller commands every body
  int fifo_priority = 80;            // the physics' and the controller's SCHED_FIFO priority
  bool reduced_coordinates = false;  // `afhub run --reduced-coordinates`: the arms as multibodies
};

struct BodiesResult {
  int bodies = 0;
  std::vector<StepPhases> steps;  // those taken while every body was commanded
  std::uint64_t commanded_steps = 0, answered_steps = 0;  // body-steps, from the world state
  LateCommands late;                                      // from the step log
  LatencyHistogram controller_compute;                    // a cycle's commands written, ns
  std::uint64_t refused_loans = 0;                        // commands not written: no shared memory
  std::uint64_t controller_overruns = 0;                  // periods the controller's loop missed
  // What the physics said when it could not publish a state; empty when it did.
  std::string physics_dropped;
};

// Runs it, with progress on stderr, against the running hub. Throws afhub::Error.
BodiesResult run_bodies_bench(const BodiesOptions& options);
// The table, with the goals met or not.
std::string bodies_table(const BodiesOptions& options, const BodiesResult& result);
// Why the run does not stand for the scene at work (as failures() for the loop).
std::vector<std::string> bodies_failures(const BodiesResult& result);

}  // namespace afhub::bench
