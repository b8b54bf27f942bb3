#pragma once
// VLP-16 wire format (user manual 63-9243, section 9): data packets (UDP 2368) and position packets (UDP 8308),
// the encoder the sim uses to produce them, and the decoder that turns them into timed points.
// The same code serves sim packets and real packets.
#include <array>
#include <cstdint>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"

namespace rotolidar {

enum class Vlp16ReturnMode : uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };
inline constexpr uint8_t kVlp16ProductId = 0x22;
inline constexpr double kVlp16FiringPeriodS = 2.304e-6;   ///< between consecutive lasers
inline constexpr double kVlp16SequencePeriodS = 55.296e-6;  ///< one firing sequence of 16 lasers
inline constexpr double kVlp16DistanceUnitM = 0.002;        ///< distance LSB
inline constexpr int kVlp16SequencesPerPacket = 24;         ///< single-return mode

/// One firing sequence of the 16 lasers, as the head measured it: the encoder's input.
/// For dual-return mode each laser carries a second (strongest/second strongest) return.
struct Vlp16FiringSequence {
  Seconds t_s = 0.0;                          ///< firing time of laser 0 on the rig clock
  uint16_t azimuth_centideg = 0;              ///< head azimuth at laser 0, [0, 36000) in 0.01 deg
  std::array<uint16_t, 16> distance_2mm{};    ///< per laser ID; 0 = no return
  std::array<uint8_t, 16> reflectivity{};     ///< per laser ID
  std::array<uint16_t, 16> distance2_2mm{};   ///< dual mode only: the other return
  std::array<uint8_t, 16> reflectivity2{};    ///< dual mode only
};

}  // namespace rotolidar
