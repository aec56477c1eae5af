// The outcome per target (loop/outcome.hpp): association of detections with the objects in the
// beam, and the statistics per object, on a synthetic set of truths and detections whose errors,
// Pd and false alarms are worked out by hand below (no run of the loop).

#include "loop/outcome.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace loop = radar_emu::loop;
namespace radar = radar_emu::radar;

namespace {

// Gate: range cell 3 m, azimuth cell 0.02 rad, elevation cell 0.2 rad, 3 sigmas; velocity folded
// into [-16, 16) m/s, range not folded.
loop::AssociationGate test_gate() {
  loop::AssociationGate g;
  g.range_cell_m = 3.0;
  g.azimuth_cell_rad = 0.02;
  g.elevation_cell_rad = 0.2;
  g.sigmas = 3.0;
  g.unambiguous_range_m = 0.0;
  g.unambiguous_velocity_mps = 16.0;
  return g;
}

loop::ObjectTruth truth(std::uint32_t id, double range_m, double azimuth_rad) {
  loop::ObjectTruth t;
  t.object_id = id;
  t.range_m = range_m;
  t.azimuth_rad = azimuth_rad;
  t.elevation_rad = 0.0;
  t.radial_velocity_mps = -70.0;
  return t;
}

// A detection as the sensor reports it: velocity folded into [-16, 16) (-70 + dv reads
// -70 + dv + 64), stated one-sigmas range_std_m, 1 mrad, 10 mrad, 0.05 m/s.
radar::Detection detection(double range_m, double azimuth_rad, double dv_mps,
                           double range_std_m = 0.1) {
  radar::Detection d;
  d.range_m = range_m;
  d.azimuth_rad = azimuth_rad;
  d.elevation_rad = 0.0;
  d.radial_velocity_mps = -70.0 + dv_mps + 64.0;
  d.range_std_m = range_std_m;
  d.azimuth_std_rad = 0.001;
  d.elevation_std_rad = 0.01;
  d.velocity_std_mps = 0.05;
  return d;
}

}  // namespace

TEST(Outcome, FoldSymmetricTakesTheNearestAlias) {
  EXPECT_DOUBLE_EQ(loop::fold_symmetric(64.5, 32.0), 0.5);
  EXPECT_DOUBLE_EQ(loop::fold_symmetric(-17.0, 32.0), 15.0);
  EXPECT_DOUBLE_EQ(loop::fold_symmetric(16.0, 32.0), -16.0);  // [-P/2, P/2)
  EXPECT_DOUBLE_EQ(loop::fold_symmetric(123.0, 0.0), 123.0);  // no period: unchanged
}

// Objects A (id 7, 1000 m, 0 rad) and B (id 9, 1020 m, 0.01 rad), both 1 m in size, in the beam
// for six frames. Range gate: 3 + 3 x 0.1 + 1 = 4.3 m (0.2 m more for a 0.2 m sigma).
//   frame 0: A at -1 m; B at +0.5 m; one at 1050 m (30 m past B: outside every gate)
//   frame 1: A at  0 m; one at 1009 m (9 m from A, 11 m from B: outside both)
//   frame 2: A at +1 m; a second return of A at -3.5 m (in A's gate, farther than the first)
//   frame 3: A at +2 m (sigma 0.2 m)
//   frame 4: A at +3 m (sigma 0.2 m)
//   frame 5: nothing
// A: in the beam 6, detected 5 (Pd 5/6), 6 detections associated; range errors -1..3 m: mean 1,
// sample std sqrt(10 / 4); stated sigmas 0.1, 0.1, 0.1, 0.2, 0.2: rms sqrt(0.11 / 5); azimuth
// error 1 mrad each (std 0); radial-velocity error +0.5 m/s each (folded back from 64.5).
// B: in the beam 6, detected 1 (Pd 1/6), range error +0.5 m. False alarms: 2 of 9 detections
// in 6 frames.
TEST(Outcome, ErrorsPdAndFalseAlarmsAgainstHandComputedValues) {
  const std::array<std::uint32_t, 2> ids{7, 9};
  loop::OutcomeTally tally(test_gate(), ids, 8, 4);
  const std::array<loop::ObjectTruth, 2> truths{truth(7, 1000.0, 0.0), truth(9, 1020.0, 0.01)};
  const std::array<double, 2> size_m{1.0, 1.0};
  // The one at 1050 m is the return of an object truth does not cover (object 42).
  radar::Detection uncovered = detection(1050.0, 0.01, 0.0);
  uncovered.object_id = 42;
  const std::vector<std::vector<radar::Detection>> frames = {
      {detection(999.0, 0.001, 0.5), detection(1020.5, 0.01, 0.0), uncovered},
      {detection(1000.0, 0.001, 0.5), detection(1009.0, 0.0, 0.0)},
      {detection(1001.0, 0.001, 0.5), detection(996.5, 0.0, 0.0)},
      {detection(1002.0, 0.001, 0.5, 0.2)},
      {detection(1003.0, 0.001, 0.5, 0.2)},
      {}};
  for (std::size_t k = 0; k < frames.size(); ++k) {
    tally.frame(truths, size_m, frames[k]);
    const auto a = tally.association();
    ASSERT_EQ(a.size(), frames[k].size()) << "frame " << k;
    if (k == 0) {
      EXPECT_EQ(a[0], 0);
      EXPECT_EQ(a[1], 1);
      EXPECT_EQ(a[2], -1);
    }
    if (k == 1) {
      EXPECT_EQ(a[1], -1);
    }
    if (k == 2) {
      EXPECT_EQ(a[1], 0);  // the second return of A: associated, not a false alarm
    }
  }
  const loop::OutcomeTotals& t = tally.totals();
  EXPECT_EQ(t.frames_scored, 6u);
  EXPECT_EQ(t.detections, 9u);
  EXPECT_EQ(t.false_alarms, 2u);
  EXPECT_EQ(t.false_alarms_on_objects, 1u);
  EXPECT_DOUBLE_EQ(t.false_alarms_per_frame(), 2.0 / 6.0);
  ASSERT_EQ(t.targets.size(), 2u);

  const loop::TargetOutcome& a = t.targets[0];
  EXPECT_EQ(a.object_id, 7u);
  EXPECT_EQ(a.frames_in_beam, 6u);
  EXPECT_EQ(a.frames_detected, 5u);
  EXPECT_EQ(a.detections_associated, 6u);
  EXPECT_DOUBLE_EQ(a.pd(), 5.0 / 6.0);
  EXPECT_EQ(a.range_m.count, 5u);
  EXPECT_NEAR(a.range_m.mean, 1.0, 1e-12);
  EXPECT_NEAR(a.range_m.std_dev(), std::sqrt(10.0 / 4.0), 1e-12);
  EXPECT_NEAR(a.range_m.stated_sigma_rms(), std::sqrt(0.11 / 5.0), 1e-12);
  EXPECT_NEAR(a.azimuth_rad.mean, 0.001, 1e-15);
  EXPECT_NEAR(a.azimuth_rad.std_dev(), 0.0, 1e-15);
  EXPECT_NEAR(a.azimuth_rad.stated_sigma_rms(), 0.001, 1e-15);
  EXPECT_NEAR(a.elevation_rad.mean, 0.0, 1e-15);
  EXPECT_NEAR(a.elevation_rad.stated_sigma_rms(), 0.01, 1e-15);
  EXPECT_NEAR(a.radial_velocity_mps.mean, 0.5, 1e-9);
  EXPECT_NEAR(a.radial_velocity_mps.std_dev(), 0.0, 1e-9);
  EXPECT_NEAR(a.radial_velocity_mps.stated_sigma_rms(), 0.05, 1e-15);

  const loop::TargetOutcome& b = t.targets[1];
  EXPECT_EQ(b.object_id, 9u);
  EXPECT_EQ(b.frames_in_beam, 6u);
  EXPECT_EQ(b.frames_detected, 1u);
  EXPECT_DOUBLE_EQ(b.pd(), 1.0 / 6.0);
  EXPECT_NEAR(b.range_m.mean, 0.5, 1e-12);
  EXPECT_EQ(b.range_m.std_dev(), 0.0);  // one sample
  EXPECT_NEAR(b.azimuth_rad.mean, 0.0, 1e-15);
}

// Two objects 4 m apart in range, one detection 1.5 m beyond the nearer: both gates hold it
// (4.3 m), the nearer in normalised distance (1.5 / 4.3 against 2.5 / 4.3) takes it, the other
// is in the beam but not detected.
TEST(Outcome, EachDetectionGoesToTheNearestObjectOnly) {
  const std::array<std::uint32_t, 2> ids{3, 4};
  loop::OutcomeTally tally(test_gate(), ids, 4, 4);
  const std::array<loop::ObjectTruth, 2> truths{truth(3, 2000.0, 0.0), truth(4, 2004.0, 0.0)};
  const std::array<double, 2> size_m{1.0, 1.0};
  const std::array<radar::Detection, 1> dets{detection(2001.5, 0.0, 0.0)};
  tally.frame(truths, size_m, dets);
  const loop::OutcomeTotals& t = tally.totals();
  EXPECT_EQ(tally.association()[0], 0);
  EXPECT_EQ(t.targets[0].frames_detected, 1u);
  EXPECT_EQ(t.targets[1].frames_detected, 0u);
  EXPECT_EQ(t.targets[1].frames_in_beam, 1u);
  EXPECT_EQ(t.false_alarms, 0u);
  EXPECT_NEAR(t.targets[0].range_m.mean, 1.5, 1e-12);
}

// The gate's size term: a detection 10 m from a point object's centre is a false alarm, from
// the centre of an object of 8 m size (gate 3 + 0.3 + 8 = 11.3 m) it is associated; an object
// not scored (its id not in the tally) takes nothing.
TEST(Outcome, ObjectSizeWidensTheGateAndUnscoredObjectsAreIgnored) {
  const std::array<std::uint32_t, 1> ids{1};
  loop::OutcomeTally tally(test_gate(), ids, 4, 4);
  const std::array<loop::ObjectTruth, 2> truths{truth(1, 3000.0, 0.0), truth(2, 3200.0, 0.0)};
  const std::array<radar::Detection, 2> dets{detection(3010.0, 0.0, 0.0),
                                             detection(3200.0, 0.0, 0.0)};
  tally.frame(truths, std::array<double, 2>{0.0, 0.0}, dets);
  EXPECT_EQ(tally.totals().false_alarms, 2u);
  tally.frame(truths, std::array<double, 2>{8.0, 0.0}, dets);
  EXPECT_EQ(tally.totals().false_alarms, 3u);
  EXPECT_EQ(tally.totals().targets[0].frames_detected, 1u);
  EXPECT_EQ(tally.totals().targets[0].frames_in_beam, 2u);
}

TEST(Outcome, RefusesAGateWithoutCells) {
  loop::AssociationGate g = test_gate();
  g.range_cell_m = 0.0;
  const std::array<std::uint32_t, 1> ids{1};
  EXPECT_THROW(loop::OutcomeTally(g, ids, 1, 1), std::invalid_argument);
}
