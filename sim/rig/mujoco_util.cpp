#include "sim/rig/mujoco_util.hpp"
#include "core/util/log.hpp"

#include <cstring>
#include <memory>
#include <mutex>

namespace rotolidar::sim {
namespace {

// MuJoCo's fatal errors: log, then unwind back to the GuardMujoco() that called into MuJoCo.
void MujocoErrorHandler(const char* msg) {
  LOG_ERROR("MuJoCo error: " << msg);
  throw MujocoError(msg);
}

void MujocoWarningHandler(const char* msg) { LOG_WARN("MuJoCo warning: " << msg); }

}  // namespace

void InstallMujocoHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = &MujocoErrorHandler;
    mju_user_warning = &MujocoWarningHandler;
  });
}

Status LoadMjcfFromString(const std::string& mjcf, const std::string& name, mjModel** model) {
  *model = nullptr;
  InstallMujocoHandlers();
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: never on the stack
  mj_defaultVFS(vfs.get());
  const int made = mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(mjcf.size()));
  if (made != 0) {
    mj_deleteVFS(vfs.get());
    return Status::Error(name + ": cannot create the in-memory MJCF file (mj_makeEmptyFileVFS = " +
                         std::to_string(made) + ")");
  }
  const int index = mj_findFileVFS(vfs.get(), name.c_str());
  std::memcpy(vfs->filedata[index], mjcf.data(), mjcf.size());
  char error[1024] = {0};
  Status status = GuardMujoco(name, [&] { *model = mj_loadXML(name.c_str(), vfs.get(), error, sizeof(error)); });
  mj_deleteVFS(vfs.get());
  if (!status) return status;
  if (*model == nullptr) return Status::Error(name + ": MuJoCo could not compile the MJCF: " + error);
  if (error[0] != '\0') LOG_WARN(name << ": MuJoCo compiler warning: " << error);
  return Status::Ok();
}

MujocoWarningCounts WarningCounts(const mjData* d) {
  MujocoWarningCounts counts{};
  for (int i = 0; i < mjNWARNING; ++i) counts[i] = d->warning[i].number;
  return counts;
}

Status NewMujocoWarnings(const MujocoWarningCounts& before, const mjData* d, const std::string& where) {
  std::string message;
  for (int i = 0; i < mjNWARNING; ++i) {
    if (d->warning[i].number == before[i]) continue;
    if (!message.empty()) message += "; ";
    message += mju_warningText(i, d->warning[i].lastinfo);
  }
  if (message.empty()) return Status::Ok();
  return Status::Error(where + ": MuJoCo warning: " + message);
}

Pose3 PoseFromMujoco(const mjtNum* pos3, const mjtNum* quat4) {
  return MakePose(Eigen::Vector3d(pos3[0], pos3[1], pos3[2]),
                  Eigen::Quaterniond(quat4[0], quat4[1], quat4[2], quat4[3]));
}

void PoseToMujoco(const Pose3& T, mjtNum* pos3, mjtNum* quat4) {
  const Eigen::Quaterniond q(T.linear());
  for (int i = 0; i < 3; ++i) pos3[i] = T.translation()[i];
  quat4[0] = q.w();
  quat4[1] = q.x();
  quat4[2] = q.y();
  quat4[3] = q.z();
}

Status FindMujocoId(const mjModel* m, int type, const std::string& name, int* id) {
  *id = mj_name2id(m, type, name.c_str());
  if (*id < 0) return Status::Error("rig model: MJCF has no element named '" + name + "'");
  return Status::Ok();
}

}  // namespace rotolidar::sim
