// calib_imu_to_velo.txt (KITTI's raw recordings) and the IMU of a KITTI sequence folder (core/io/kitti.hpp).
#include <string>
#include <vector>

#include "core/io/kitti.hpp"
#include "core/io/kitti_text.hpp"
#include "core/util/text.hpp"

namespace rotolidar {

using namespace kitti_text;

Status ReadKittiImuCalib(const std::string& path, KittiImuCalib* calib) {
  std::vector<std::string> lines;
  if (Status s = ReadLines(path, &lines); !s) return s;
  KittiImuCalib out;
  std::vector<double> R, T;
  bool has_time = false;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = int(i) + 1;
    const std::vector<std::string> tokens = SplitWhitespace(lines[i]);
    if (tokens.empty()) continue;
    const std::string& head = tokens[0];
    std::vector<double>* target = head == "R:" ? &R : head == "T:" ? &T : nullptr;
    if (head == "calib_time:") {
      if (has_time) return Status::Error(Where(path, line) + "key 'calib_time' given twice");
      has_time = true;
      out.calib_time = lines[i].substr(lines[i].find(':') + 1);
      out.calib_time.erase(0, out.calib_time.find_first_not_of(" \t"));
      continue;
    }
    if (!target) return Status::Error(Where(path, line) + "unknown key '" + head + "' (calib_time: R: T:)");
    if (!target->empty()) return Status::Error(Where(path, line) + "key '" + head + "' given twice");
    const std::string key = head.substr(0, 1);
    if (Status s = ParseNumbers(path, line, tokens, 1, target == &R ? 9 : 3, key, target); !s) return s;
    if (target == &R) {
      Matrix34d M = Matrix34d::Zero();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) M(r, c) = R[size_t(3 * r + c)];
      Pose3 rotation;
      if (Status s = ToPose(path, line, "R", M, &rotation); !s) return s;
      out.T_velo_imu.linear() = rotation.linear();
    }
  }
  if (R.empty()) return Status::Error(path + ": key 'R' missing");
  if (T.empty()) return Status::Error(path + ": key 'T' missing");
  out.T_velo_imu.translation() = Eigen::Vector3d(T[0], T[1], T[2]);
  *calib = out;
  return Status::Ok();
}

Status WriteKittiImuCalib(const std::string& path, const KittiImuCalib& calib) {
  std::string text;
  if (!calib.calib_time.empty()) text += "calib_time: " + calib.calib_time + "\n";
  text += "R:";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) text += " " + FormatNumber(calib.T_velo_imu.linear()(r, c));
  text += "\nT:";
  for (int r = 0; r < 3; ++r) text += " " + FormatNumber(calib.T_velo_imu.translation()(r));
  return WriteText(path, text + "\n");
}

}  // namespace rotolidar
