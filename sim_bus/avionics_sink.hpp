#pragma once
// The avionics under test, simulated: receives the radar's detection frames and reassembles
// the detection lists with the ICD decoder, as a real consumer of the ICD would.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "io/can_frame.hpp"
#include "io/detection_icd.hpp"

namespace radar_emu::sim_bus {

class AvionicsSink {
 public:
  /// `max_lists` complete lists are kept (reserved here; later ones are counted, not stored).
  explicit AvionicsSink(std::size_t max_lists);

  /// Reads every pending frame from `bus` and decodes it. Returns lists completed by this call.
  /// Real-time safe.
  std::size_t poll(io::CanEndpoint& bus) noexcept;

  [[nodiscard]] const std::vector<io::icd::DetectionList>& lists() const noexcept { return lists_; }
  [[nodiscard]] std::uint64_t lists_completed() const noexcept { return completed_; }
  [[nodiscard]] std::uint64_t lists_not_stored() const noexcept { return not_stored_; }
  [[nodiscard]] std::uint64_t frames_seen() const noexcept { return frames_; }
  [[nodiscard]] std::uint64_t frames_ignored() const noexcept { return ignored_; }
  [[nodiscard]] const io::icd::ListDecoder& decoder() const noexcept { return decoder_; }

 private:
  io::icd::ListDecoder decoder_;
  std::vector<io::icd::DetectionList> lists_;
  std::size_t max_lists_;
  std::uint64_t completed_ = 0;
  std::uint64_t not_stored_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t ignored_ = 0;
};

}  // namespace radar_emu::sim_bus
