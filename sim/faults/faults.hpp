#pragma once
// Fault injection in the twin (docs/noise_models.md, "Faults"): what a real rig's network, encoder, IMU and
// LiDAR do when they misbehave, applied as a filter between the sim's streams and the RecordingWriter. All off
// by default: a writer with no fault configured passes every message through untouched (the recording's bytes
// are those of a run without the filter).
//
//  * LiDAR data packets (UDP 2368; position packets always pass): lost at random and in bursts, duplicated,
//    swapped with a later one, or blinded (every distance and reflectivity zeroed: a covered sensor).
//  * Encoder: frozen over an interval (samples keep coming, with the last count before the interval).
//  * IMU: dropped over an interval and/or at random; clipped to a range per axis (saturation).
//
// Times: each fault's interval is on the stamps of the stream it acts on, as written: a LiDAR packet's capture
// time (pcap record time, rig clock), an IMU or encoder sample's t_s (its sensor clock: rig time plus the
// configured clock offset and drift, milliseconds at most). Intervals are half open, [start_s, start_s +
// duration_s). Randomness: each fault draws from its own stream RandomStream(run_seed, "fault.<name>")
// (core/util/rng.hpp), one draw per input message whether or not an earlier fault dropped it, so changing one
// fault never changes which messages another fault hits. The truth channel is untouched; FaultTruth (written to
// truth/faults.yaml) records what was injected.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/io/recording.hpp"
#include "core/types/messages.hpp"
#include "core/util/rng.hpp"
#include "core/util/status.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

/// [start_s, start_s + duration_s) on a stream's stamps [s]; off while duration_s is 0.
struct FaultInterval {
  double start_s = 0.0;
  double duration_s = 0.0;
  bool Enabled() const { return duration_s > 0.0; }
  bool Contains(double t_s) const { return Enabled() && t_s >= start_s && t_s < start_s + duration_s; }
};

/// Lost data packets: each independently with `probability`, plus bursts that start as a Poisson process of
/// `burst_rate_hz` (on capture time, from the first data packet) and drop `burst_length_packets` consecutive
/// data packets each (a burst starting inside another restarts its count).
struct LidarLossFault {
  double probability = 0.0;         ///< [0, 1)
  double burst_rate_hz = 0.0;       ///< mean bursts per second [1/s]; 0 = no bursts
  int burst_length_packets = 10;    ///< data packets dropped per burst, >= 1
};

/// A data packet is followed by a copy of itself (same payload and capture time) with `probability`.
struct LidarDuplicateFault {
  double probability = 0.0;  ///< [0, 1]
};

/// With `probability` a data packet A (not already held for another swap) trades places with the data packet
/// k later, k uniform in [1, max_distance_packets]; the packets between keep their places. Capture times stay
/// in their slots (a capture's record times never go back): A's slot carries the later packet's payload.
struct LidarReorderFault {
  double probability = 0.0;       ///< [0, 1]
  int max_distance_packets = 8;   ///< [1, 1000]
};

/// IMU samples dropped over `start_s`/`duration_s` and, anywhere, each with `probability`.
struct ImuDropoutFault {
  double start_s = 0.0;
  double duration_s = 0.0;
  double probability = 0.0;  ///< [0, 1)
  FaultInterval Interval() const { return {start_s, duration_s}; }
};

/// Each gyro / accelerometer axis clipped to [-range, +range]; 0 = no clipping.
struct ImuSaturationFault {
  double gyro_range_radps = 0.0;  ///< [rad/s]
  double accel_range_mps2 = 0.0;  ///< [m/s^2]
};

/// The sim config's `faults:` section (sim/faults/faults_yaml.cpp; keys as the field names).
struct FaultConfig {
  LidarLossFault lidar_loss;
  LidarDuplicateFault lidar_duplicate;
  LidarReorderFault lidar_reorder;
  FaultInterval lidar_blind;     ///< data packets keep coming with every distance 0 (no points)
  FaultInterval encoder_freeze;  ///< samples keep coming with the last count before the interval
  ImuDropoutFault imu_dropout;
  ImuSaturationFault imu_saturation;

  bool LidarEnabled() const;
  bool Enabled() const;
  /// False naming the field ("faults.lidar_loss.probability: must be in [0, 1)") unless every value is finite,
  /// probabilities are in range, rates and ranges >= 0, start_s >= 0, duration_s >= 0, burst_length_packets in
  /// [1, 1000000] and max_distance_packets in [1, 1000].
  bool Validate(std::string* error) const;
};

/// What was injected (truth/faults.yaml). Intervals are [first, last] stamp of the messages the fault hit [s].
struct LidarFaultTruth {
  size_t data_packets_in = 0;   ///< data packets the sim wrote into the filter
  size_t data_packets_out = 0;  ///< data packets that reached lidar.pcap (duplicates included)
  size_t lost_random = 0;
  size_t lost_burst = 0;
  std::vector<std::array<double, 3>> bursts;  ///< per burst: first and last dropped capture time [s], packets
  size_t duplicated = 0;                      ///< extra copies written
  size_t swaps = 0;
  /// Data packets written after a newer one whose own stamp had not been written yet: what a reordering
  /// buffer (core/wire/packet_orderer.hpp) counts as reordered; k per swap of distance k.
  size_t arrived_after_newer = 0;
  size_t blinded = 0;                          ///< data packets written with every distance zeroed
  std::array<double, 2> blinded_interval_s{};  ///< capture times of the first and last blinded packet
};

struct EncoderFaultTruth {
  size_t frozen_samples = 0;                  ///< samples written with the stale count
  uint32_t frozen_count = 0;                  ///< the count they carried
  std::array<double, 2> frozen_interval_s{};  ///< stamps of the first and last frozen sample
};

struct ImuFaultTruth {
  size_t samples_in = 0;
  size_t dropped_interval = 0;                 ///< dropped inside imu_dropout's interval
  std::array<double, 2> dropped_interval_s{};  ///< stamps of the first and last sample dropped there
  size_t dropped_random = 0;
  size_t saturated_samples = 0;  ///< written samples with at least one axis clipped
};

struct FaultTruth {
  FaultConfig config;
  LidarFaultTruth lidar;
  EncoderFaultTruth encoder;
  ImuFaultTruth imu;
};

/// Zeroes every distance and reflectivity of a 1206-byte VLP-16 data payload (timestamp, azimuths, mode kept);
/// any other payload is left as it is.
void BlindVlp16Payload(std::vector<uint8_t>* payload);

/// The filter: the RecordingWriter's Write overloads, each fault applied on the way. Holds at most the packets of
/// one pending swap (max_distance_packets data packets plus the position packets between them); Close() writes
/// them. Camera frames pass untouched. Not thread-safe. A failed write of the wrapped writer is returned as is.
class FaultyWriter {
 public:
  /// `out` (already opened) must outlive this writer; `config` must be valid (FaultConfig::Validate).
  FaultyWriter(const FaultConfig& config, uint64_t run_seed, RecordingWriter* out);

  Status Write(const LidarPacket& packet);
  Status Write(const ImuSample& sample);
  Status Write(const EncoderSample& sample);
  Status Write(const CameraFrame& frame) { return out_->Write(frame); }
  /// Writes the packets still held for a swap (the swap then never happens) and closes the wrapped writer.
  Status Close();

  const FaultTruth& truth() const { return truth_; }
  RecordingWriter* inner() const { return out_; }

 private:
  struct Held {
    LidarPacket packet;
    bool data = false;
    bool copy = false;  ///< a duplicate (never a swap's partner)
    size_t index = 0;   ///< input order of a data packet (a duplicate shares its original's)
  };
  bool Lost(double t_s, double u_loss);
  bool InBurst(double t_s);
  Status Reorder(Held held, bool start_swap, int distance);
  Status Emit(const Held& held);
  Status FlushHeld();

  FaultConfig config_;
  RecordingWriter* out_;
  RandomStream loss_rng_, burst_rng_, duplicate_rng_, reorder_rng_, imu_dropout_rng_;
  FaultTruth truth_;
  bool lidar_on_ = false, any_on_ = false;
  double next_burst_s_ = -1.0;  ///< start of the next burst; < 0 before the first data packet
  int burst_left_ = 0;          ///< data packets the current burst still drops
  std::vector<Held> held_;      ///< from the swap's first packet on
  int swap_countdown_ = 0;      ///< data packets to come before the swap partner
  std::vector<uint8_t> seen_;   ///< per input index: written already
  size_t newest_written_ = 0;
  bool any_written_ = false;
  bool have_encoder_count_ = false;
  uint32_t last_encoder_count_ = 0;  ///< last count written before the freeze
};

/// The `faults:` section: keys as the fields above (a mapping per fault); unknown keys are errors naming
/// file:line; the result is validated (errors name the field). *config is untouched on error.
Status ParseFaultConfig(const std::string& file, const YAML::Node& node, FaultConfig* config);
void EmitFaultConfig(YAML::Emitter& out, const FaultConfig& config);
/// Writes <recording_dir>/truth/faults.yaml (the folder must exist); fails naming the file.
Status WriteFaultTruth(const std::string& recording_dir, const FaultTruth& truth);
/// Reads truth/faults.yaml back; errors name file:line and the field.
Status ReadFaultTruth(const std::string& recording_dir, FaultTruth* truth);

}  // namespace rotolidar::sim
