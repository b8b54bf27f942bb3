#pragma once
// `rotolidar decode`: VLP-16 packets (pcap or headerless raw payloads) -> per-point CSV and binary PLY, with
// revolution statistics. The library function behind the command; the CLI only parses options.
#include <cstddef>
#include <ostream>
#include <string>

#include "core/wire/vlp16.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct DecodeOptions {
  std::string input_path;     ///< a .pcap/.pcapng file, or concatenated 1206-byte payloads with raw = true
  std::string output_prefix;  ///< writes <prefix>.csv, <prefix>.ply and <prefix>.decode.yaml (resolved options)
  bool raw = false;
  /// Range limits, return filter, clock offset and dual-return duplicates, as the core decoder takes them.
  Vlp16DecoderConfig decoder;
  double epoch_unix_s = 0.0;          ///< pcap only: record time - this = t_capture_s [s]
  double cut_azimuth_deg = 0.0;       ///< revolutions start where the azimuth crosses this [deg]
  int revolution = -1;  ///< write only this scan (0 = the first, usually partial, scan); -1 = every point
  bool strict = false;  ///< stop at the first malformed packet/record instead of counting it
  bool Validate(std::string* error) const;
};

struct DecodeSummary {
  std::size_t packets = 0;           ///< data packets decoded
  std::size_t position_packets = 0;
  std::size_t skipped_frames = 0;    ///< pcap frames that were not VLP-16 traffic
  std::size_t malformed = 0;         ///< packets/records rejected (first message in first_error)
  std::string first_error;
  std::size_t points = 0;            ///< points decoded (after range and return filters)
  std::size_t merged_dual_duplicates = 0;  ///< dual mode: points that stand for two identical returns (return 2)
  std::size_t points_written = 0;    ///< rows in the CSV/PLY (all points, or those of `revolution`)
  std::size_t scans = 0;             ///< pieces the splitter produced, partial first and last included
  std::size_t full_revolutions = 0;  ///< scans bounded by a cut crossing on both sides
  double t_first_s = 0.0, t_last_s = 0.0;  ///< rig times of the first and last point
};

/// Decodes `options.input_path` and writes the outputs. Fails (message names the file) on invalid options,
/// unreadable input, unwritable outputs, or with strict = true on the first malformed packet (which is otherwise
/// counted in summary->malformed and skipped). A run that yields no point fails too, saying why: a pcap without
/// VLP-16 data packets names the UDP ports and payload sizes it holds (PcapReader::NoVlp16DataError); an empty
/// raw file, packets that were all malformed, points all outside the range/return filters and a `revolution`
/// past the last scan each have their own message. *summary is filled in every case.
/// CSV header: x,y,z,intensity,ring,azimuth,return,time_s (metres in the lidar frame, reflectivity 0..255, ring
/// 0..15 by elevation, azimuth [deg], return 0 = strongest / 1 = last / 2 = both (dual mode: the strongest was
/// the last), rig time [s]). PLY: binary little-endian, one vertex per row with the same properties (float x y z
/// intensity, uchar ring, float azimuth, uchar return, double time_s).
Status RunDecode(const DecodeOptions& options, DecodeSummary* summary);

/// "all" | "strongest" | "last".
bool ParseReturnFilter(const std::string& text, Vlp16ReturnFilter* filter);
void PrintDecodeSummary(const DecodeSummary& summary, std::ostream& os);

}  // namespace rotolidar::bench
