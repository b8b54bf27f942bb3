#pragma once
// The one clock of rotolidar ("rig clock").
//
// Every timestamp in core/ is a double in seconds on the rig clock. The rig clock's epoch is the start of the
// recording: the sim starts it at t = 0; a real rig's logger subtracts its start time and records the absolute
// epoch in calib.yaml (`epoch_unix_s`). Keeping the epoch near zero keeps doubles at ~1e-15 s resolution
// for days of data. Sensors with their own clocks (the VLP-16 counts microseconds past the top of the hour) are
// mapped onto the rig clock by the reader, with the offsets in calib.yaml. See docs/frames.md ("Clock").
namespace rotolidar {

using Seconds = double;  ///< a time on the rig clock, or a duration, in seconds

}  // namespace rotolidar
