#pragma once
// Owned storage for one captured frame (SensorCapture's spans point into it): what the cube
// writer allocates per slot at setup, and what its test and benchmark allocate alike.
// Setup only: it allocates. Not copyable (the spans would point into the source); movable
// (a vector's move keeps its buffer, so the spans stay valid).

#include <complex>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "radar/sensor/sensor.hpp"

namespace radar_emu::radar {

struct CaptureStorage {
  /// Room for `shape`'s image, `max_false_alarms_per_beam` false alarms in each beam and
  /// `max_returns` returns; `capture` points into it.
  CaptureStorage(const CaptureShape& shape, std::size_t max_false_alarms_per_beam,
                 std::size_t max_returns)
      : image(shape.image_values()),
        power(shape.image_values()),
        synthesised(shape.beams * shape.velocity_bins),
        alarms(shape.beams * max_false_alarms_per_beam),
        alarm_count(shape.beams),
        returns(max_returns) {
    capture.image = image;
    capture.power = power;
    capture.synthesised = synthesised;
    capture.false_alarms = alarms;
    capture.false_alarm_count = alarm_count;
    capture.returns = returns;
  }
  CaptureStorage(const CaptureStorage&) = delete;
  CaptureStorage& operator=(const CaptureStorage&) = delete;
  CaptureStorage(CaptureStorage&&) = default;
  CaptureStorage& operator=(CaptureStorage&&) = default;
  ~CaptureStorage() = default;

  std::vector<std::complex<float>> image;
  std::vector<float> power;
  std::vector<RowSpan> synthesised;
  std::vector<FalseAlarm> alarms;
  std::vector<std::uint32_t> alarm_count;
  std::vector<CapturedReturn> returns;
  SensorCapture capture;
};

}  // namespace radar_emu::radar
