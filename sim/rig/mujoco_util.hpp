#pragma once
// MuJoCo 2.2.2 at the sim boundary: its error/warning handlers routed into the project's logging, loading an
// MJCF held in memory (2.2.2 has no load-from-string call: through a heap-allocated virtual file system), the
// instability warnings as a Status, and pose conversions.
//
// MuJoCo reports fatal errors through the global `mju_user_error` hook; the default hook prints, waits for Enter
// and exits. InstallMujocoHandlers() replaces it with one that logs and throws MujocoError. The throw unwinds
// through MuJoCo's C frames (Debian's libmujoco carries .eh_frame unwind tables, and C frames own nothing that
// needs cleanup); GuardMujoco() catches it and returns a Status, so library code never exits. After an error the
// mjData involved is in an undefined state: reset it (mj_resetData) before using it again.
// Warnings (`mju_user_warning`, e.g. "Nan, Inf or huge value in QACC") are logged as LOG_WARN; each mjData also
// counts them (mjData::warning), which NewMujocoWarnings() turns into a Status.
#include <array>
#include <stdexcept>
#include <string>
#include <utility>

#include <mujoco/mujoco.h>

#include "core/types/geometry.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {

/// Thrown by the installed mju_user_error handler; caught by GuardMujoco (never escapes sim/).
struct MujocoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Installs the logging error/warning handlers (once per process; thread-safe, idempotent). Every function in
/// sim/ that calls MuJoCo calls this first.
void InstallMujocoHandlers();

/// Runs fn() (which calls MuJoCo) and turns a MuJoCo error into Status::Error("<what>: MuJoCo error: <msg>").
template <typename Fn>
Status GuardMujoco(const std::string& what, Fn&& fn) {
  InstallMujocoHandlers();
  try {
    std::forward<Fn>(fn)();
  } catch (const MujocoError& e) {
    return Status::Error(what + ": MuJoCo error: " + e.what());
  }
  return Status::Ok();
}

/// Compiles MJCF text held in memory. `name` is the virtual file name MuJoCo reports in its messages (no path).
/// On success *model owns a new mjModel (free with mj_deleteModel); on failure *model is null and the Status
/// carries MuJoCo's compiler message. The VFS (~2 MB in 2.2.2) lives on the heap only during the call.
Status LoadMjcfFromString(const std::string& mjcf, const std::string& name, mjModel** model);

/// Snapshot of mjData::warning[].number, to compare before/after a step.
using MujocoWarningCounts = std::array<int, mjNWARNING>;
MujocoWarningCounts WarningCounts(const mjData* d);

/// Ok when no warning counter grew since `before`; otherwise an error naming each new warning (MuJoCo's text)
/// and `where` (e.g. "step 123, t = 0.123 s").
Status NewMujocoWarnings(const MujocoWarningCounts& before, const mjData* d, const std::string& where);

/// MuJoCo position + quaternion (w, x, y, z) <-> Pose3.
Pose3 PoseFromMujoco(const mjtNum* pos3, const mjtNum* quat4);
void PoseToMujoco(const Pose3& T, mjtNum* pos3, mjtNum* quat4);

/// Id of a named element of type `type` (mjOBJ_BODY, ...), or an error naming the element when it is missing.
Status FindMujocoId(const mjModel* m, int type, const std::string& name, int* id);

}  // namespace rotolidar::sim
