// Event substeps (simulation.event_substeps): elastic steps in which a
// contact event falls are retaken as halves, recursively. A cube dropped on
// an edge, with friction and BBI, run with a coarse step refined around
// its touch-downs is compared with the same run at the fine step
// throughout.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/errors.hpp"
#include "dynamics/dynamics_run.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "io/config.hpp"

namespace msfab {
namespace {

std::string drop_scene(double time_step, int event_substeps) {
  return R"(
name: oblique-drop
materials:
  - {name: rigur, E: 0.65e9, nu: 0.45, density: 1200, damping_a: 0, damping_b: 1.64e-4}
geometry:
  voxel_size: 0.005
  boxes:
    - {material: rigur, min: [0, 0, 0], max: [0.01, 0.01, 0.01]}
placement:
  rotation_deg: [25, 35, 0]
  translation: [0, 0, 0.02]
obstacles:
  - {type: ground, z: 0, surface: table}
friction:
  default: 0.5
simulation:
  time_step: )" +
         std::to_string(time_step) +
         R"(
  duration: 0.1
  impact: bbi
  output_every: 1000
  event_substeps: )" +
         std::to_string(event_substeps) + "\n";
}

Trajectory run(double time_step, int event_substeps) {
  return run_dynamics_scene(
      read_dynamics_scene(Config::from_string(drop_scene(time_step, event_substeps), "drop.yaml")));
}

// Largest centre-of-mass distance and rotation difference between a run and
// a finer one whose step is `ratio` times shorter, at the coarse run's times.
struct Gap {
  double position = 0, rotation = 0;
};
Gap gap(const Trajectory& coarse, const Trajectory& fine, int ratio) {
  Gap g;
  for (size_t i = 0; i < coarse.samples.size(); ++i) {
    const TrajectorySample& a = coarse.samples[i];
    const TrajectorySample& b = fine.samples.at(i * ratio);
    EXPECT_NEAR(a.time, b.time, 1e-9);
    g.position = std::max(g.position, (a.center_of_mass - b.center_of_mass).norm());
    g.rotation = std::max(g.rotation, (a.rotation - b.rotation).norm());
  }
  return g;
}

TEST(EventSubsteps, RefiningAroundContactEventsApproachesTheFineStep) {
  const double h = 4e-4;
  const Trajectory fine = run(h / 4, 0);
  const Trajectory coarse = run(h, 0);
  const Trajectory refined = run(h, 2);
  ASSERT_EQ(refined.samples.size(), coarse.samples.size());
  ASSERT_EQ(fine.samples.size(), 4 * (coarse.samples.size() - 1) + 1);

  // Without substeps every elastic step is one Newmark step.
  EXPECT_EQ(coarse.elastic_steps, static_cast<std::int64_t>(coarse.samples.size() - 1));
  EXPECT_EQ(coarse.event_substeps, 0);
  EXPECT_EQ(refined.event_substeps, 2);
  // Refinement happened, but only around events: far fewer steps than the
  // fine run.
  EXPECT_GT(refined.elastic_steps, coarse.elastic_steps);
  EXPECT_LT(refined.elastic_steps, fine.elastic_steps);

  // Before the first touch-down the three runs fall freely under gravity,
  // which the trapezoidal rule integrates exactly at any step.
  size_t first_contact = 0;
  while (first_contact < fine.samples.size() && fine.samples[first_contact].active_contacts == 0) ++first_contact;
  ASSERT_GT(first_contact, 8u) << "the cube must fall for a while before it lands";
  for (size_t i = 0; 4 * i + 4 < first_contact; ++i) {
    EXPECT_LT((coarse.samples[i].center_of_mass - fine.samples[4 * i].center_of_mass).norm(), 1e-12);
    EXPECT_LT((refined.samples[i].center_of_mass - fine.samples[4 * i].center_of_mass).norm(), 1e-12);
  }

  const Gap uniform = gap(coarse, fine, 4), adaptive = gap(refined, fine, 4);
  std::printf(
      "  oblique drop, h = %.1e s against h/4 throughout: uniform h: |dx| %.3e m, |dtheta| %.3e rad; "
      "h refined around events (%lld steps for %zu): |dx| %.3e m, |dtheta| %.3e rad; fine: %lld steps\n",
      h, uniform.position, uniform.rotation, static_cast<long long>(refined.elastic_steps), coarse.samples.size() - 1,
      adaptive.position, adaptive.rotation, static_cast<long long>(fine.elastic_steps));
  EXPECT_LT(adaptive.position, 0.5 * uniform.position);
}

TEST(EventSubsteps, BadLevelsAreInputErrors) {
  for (int levels : {-1, 13}) {
    try {
      run(1e-4, levels);
      FAIL() << "event_substeps " << levels << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("event_substeps"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace msfab
