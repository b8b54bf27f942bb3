// Scan-to-map registration on real LiDAR data ($ROTOLIDAR_DATA, skipped when absent):
//  - KITTI 00 frames 0..10 (HDL-64E bins of kitti00/): every consecutive pair k -> k+1 registered (frame k+1 into
//    a map of frame k) and compared with two independent stereo SLAM results on the same frames, ORB-SLAM2 and
//    S-PTAM, converted to the LiDAR frame (T_velo = Tr^-1 * P_k^-1 * P_k+1 * Tr), and with PCL's GICP (through
//    core's GicpMatcher). KITTI's official ground truth is wrong for frames 0..~13 of sequence 00 (a constant
//    0.86 m per frame while the car accelerates from ~0.68 m; docs/registration.md): it is printed, and the test
//    asserts that our 0->1 step is far closer to the stereo references than to it. Frames 0..5 also run as
//    sequential odometry through a growing LocalMap, checked against direct registration to frame 0.
//  - the fast_gicp / small_gicp scan pair against their reference T_target_source (5 cm / 1 deg, both ways).
// Neither set carries ring indices, so features are chosen here by local PCA shape (planarity / linearity of
// each voxel-downsampled point's neighbourhood), independent of core/features.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <Eigen/Eigenvalues>

#include "core/io/kitti.hpp"
#include "core/registration/gicp_matcher.hpp"
#include "core/registration/scan_to_map.hpp"
#include "tests/common/kitti00_reference.hpp"
#include "tests/common/test_data.hpp"

namespace rotolidar {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZI>;

struct PcaFeatureConfig {
  double min_range_m = 2.0;     ///< drops the vehicle itself and the invalid points at the origin
  double voxel_m = 0.2;         ///< downsampling before the neighbourhood analysis (fast_gicp's test: 0.2)
  int neighbours = 20;          ///< k for the local covariance
  double max_radius_m = 1.5;    ///< the k-th neighbour must be this close (sparse far points are skipped)
  double min_planarity = 0.6;   ///< (l2 - l3) / l1
  double min_linearity = 0.75;  ///< (l1 - l2) / l1
};

/// Planar points -> planar and less_flat; linear points -> edge and less_sharp (all in the cloud's own frame).
FeatureSet PcaFeatures(const Cloud& raw, const PcaFeatureConfig& c) {
  Cloud::Ptr kept(new Cloud);
  for (const auto& p : raw.points)
    if (std::isfinite(p.x) && Eigen::Vector3f(p.x, p.y, p.z).norm() >= c.min_range_m) kept->push_back(p);
  Cloud::Ptr down(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZI> grid;
  grid.setInputCloud(kept);
  grid.setLeafSize(float(c.voxel_m), float(c.voxel_m), float(c.voxel_m));
  grid.filter(*down);
  pcl::KdTreeFLANN<pcl::PointXYZI> tree;
  tree.setInputCloud(down);
  FeatureSet f;
  std::vector<int> idx;
  std::vector<float> sq;
  for (const auto& p : down->points) {
    if (tree.nearestKSearch(p, c.neighbours, idx, sq) < c.neighbours || sq.back() > c.max_radius_m * c.max_radius_m)
      continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int i : idx) mean += (*down)[size_t(i)].getVector3fMap().cast<double>();
    mean /= double(idx.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int i : idx) {
      const Eigen::Vector3d d = (*down)[size_t(i)].getVector3fMap().cast<double>() - mean;
      cov += d * d.transpose();
    }
    const Eigen::Vector3d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();  // ascending
    if (!(l(2) > 0)) continue;
    if ((l(1) - l(0)) / l(2) >= c.min_planarity) f.planar.push_back(p);
    else if ((l(2) - l(1)) / l(2) >= c.min_linearity) f.edge.push_back(p);
  }
  f.less_flat = f.planar;
  f.less_sharp = f.edge;
  return f;
}

/// KITTI velodyne .bin: float32 x y z reflectance per point.
Cloud LoadKittiBin(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  Cloud cloud;
  float v[4];
  while (in.read(reinterpret_cast<char*>(v), sizeof(v))) {
    pcl::PointXYZI p;
    p.x = v[0];
    p.y = v[1];
    p.z = v[2];
    p.intensity = v[3];
    cloud.push_back(p);
  }
  return cloud;
}

/// Rows of 12 numbers (3x4 row-major [R t]) or 16 (4x4); one pose per row.
std::vector<Pose3> LoadPoses(const std::string& path) {
  std::ifstream in(path);
  std::vector<Pose3> poses;
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  const size_t stride = v.size() % 12 == 0 ? 12 : 16;
  for (size_t k = 0; k + stride <= v.size(); k += stride) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 4; ++col) M(r, col) = v[k + size_t(4 * r + col)];
    poses.push_back(MakePose(M.block<3, 1>(0, 3), Eigen::Quaterniond(M.block<3, 3>(0, 0))));
  }
  return poses;
}


LocalMap SingleKeyframeMap(const FeatureSet& features) {
  LocalMapConfig config;
  config.edge_voxel_m = 0.2;  // = the feature voxel: the map keeps every feature point
  config.planar_voxel_m = 0.2;
  LocalMap map(config);
  map.AddKeyframe(features, Pose3::Identity());
  return map;
}

/// Points beyond min_range_m as Eigen vectors, voxel-downsampled (for PCL GICP through core's GicpMatcher).
std::vector<Eigen::Vector3d> GicpInput(const Cloud& raw, double min_range_m, double voxel_m) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : raw.points) {
    const Eigen::Vector3d v(p.x, p.y, p.z);
    if (v.allFinite() && v.norm() >= min_range_m) points.push_back(v);
  }
  return VoxelDownsample(points, voxel_m);
}

using namespace testdata;  // NOLINT: the kitti00 references and bounds
constexpr size_t kKittiFrames = kKitti00Frames;

struct KittiFrames {
  std::vector<FeatureSet> features;                      ///< PCA features per frame (LiDAR frame of that scan)
  std::vector<std::vector<Eigen::Vector3d>> gicp_input;  ///< 0.3 m voxel clouds for PCL GICP
  /// Reference steps T_velo(k)_velo(k+1), k = 0..9, of ORB-SLAM2, S-PTAM and the official ground truth.
  std::vector<Pose3> orb, sptam, official;
  std::string error;                                     ///< non-empty when a file is missing or short
};

KittiFrames LoadKitti(const std::string& dir) {
  KittiFrames k;
  KittiCalib calib;
  if (const Status s = ReadKittiCalib(dir + "calib_00.txt", &calib); !s) {
    k.error = s.message;
    return k;
  }
  const std::pair<const char*, std::vector<Pose3>*> refs[] = {
      {"orbslam2_stereo_00_frames_0-10_cam0.txt", &k.orb},
      {"sptam_stereo_00_frames_0-10_cam0.txt", &k.sptam},
      {"gt_poses_00_frames_0-10_cam0.txt", &k.official}};
  for (const auto& [file, ref] : refs) {
    if (const Status s = ReadVeloSteps(dir + file, calib.T_cam0_velo, ref); !s) {
      k.error = s.message;
      return k;
    }
  }
  for (size_t i = 0; i < kKittiFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "velodyne/%06zu.bin", i);
    const Cloud cloud = LoadKittiBin(dir + name);
    if (cloud.size() < 100000) {
      k.error = dir + name + ": expected > 100000 points";
      return k;
    }
    k.features.push_back(PcaFeatures(cloud, PcaFeatureConfig()));
    k.gicp_input.push_back(GicpInput(cloud, PcaFeatureConfig().min_range_m, 0.3));
  }
  return k;
}

class Kitti00 : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string dir;
    if (testdata::FindDataFolder("kitti00", &dir).empty()) data_ = new KittiFrames(LoadKitti(dir + "/"));
  }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  void SetUp() override {
    ROTOLIDAR_REQUIRE_DATA(dir, "kitti00");
    ASSERT_NE(data_, nullptr);
    ASSERT_TRUE(data_->error.empty()) << data_->error;
  }
  static Pose3 ConstantVelocityGuess(const std::vector<Pose3>& est) {  // T_0_k from T_0_{k-1}, T_0_{k-2}
    const size_t n = est.size();
    return n < 2 ? est.back() : est[n - 1] * (est[n - 2].inverse() * est[n - 1]);
  }
  static KittiFrames* data_;
};
KittiFrames* Kitti00::data_ = nullptr;

struct StepError {
  double t_m = 0.0, r_deg = 0.0;
};
StepError Diff(const Pose3& a, const Pose3& b) { return {TranslationError(a, b), RotationErrorDeg(a, b)}; }

// Bounds: kMaxStereoStepM / kMaxStereoStepDeg and the RMS rule (tests/common/kitti00_reference.hpp).

GicpConfig KittiGicpConfig() {
  GicpConfig c;
  c.max_correspondence_m = 1.0;
  c.max_iterations = 100;
  c.transformation_epsilon = 1e-10;
  return c;
}

TEST_F(Kitti00, ConsecutivePairsAgreeWithBothStereoReferences) {
  const KittiFrames& d = *data_;
  GicpMatcher gicp(KittiGicpConfig());
  std::vector<double> orb_m, sptam_m, refs_m;  // per step translation errors [m]
  Pose3 guess = Pose3::Identity();              // 0->1: ~0.7 m off; then the previous step (constant velocity)
  for (size_t k = 0; k + 1 < kKittiFrames; ++k) {
    const ScanToMapResult r = Register(d.features[k + 1], SingleKeyframeMap(d.features[k]), guess, {});
    ASSERT_TRUE(r.converged) << k << "->" << k + 1 << ": " << r.message;
    gicp.SetTarget(d.gicp_input[k]);
    const RegistrationResult g = gicp.Align(d.gicp_input[k + 1], guess);
    ASSERT_TRUE(g.converged) << "PCL GICP " << k << "->" << k + 1;
    const Pose3& ours = r.T_map_scan;  // T_velo(k)_velo(k+1)
    const StepError orb = Diff(ours, d.orb[k]), sptam = Diff(ours, d.sptam[k]), refs = Diff(d.orb[k], d.sptam[k]);
    const StepError official = Diff(ours, d.official[k]), pcl = Diff(ours, g.T_target_source);
    std::printf("KITTI %zu->%zu: ours %.4f m | vs ORB-SLAM2 %.2f cm %.3f deg | vs S-PTAM %.2f cm %.3f deg | "
                "ORB vs S-PTAM %.2f cm %.3f deg | vs official %.2f cm %.3f deg (official %.4f m) | "
                "vs PCL GICP %.2f cm %.3f deg\n",
                k, k + 1, ours.translation().norm(), 100 * orb.t_m, orb.r_deg, 100 * sptam.t_m, sptam.r_deg,
                100 * refs.t_m, refs.r_deg, 100 * official.t_m, official.r_deg, d.official[k].translation().norm(),
                100 * pcl.t_m, pcl.r_deg);
    EXPECT_LT(orb.t_m, kMaxStereoStepM) << k;
    EXPECT_LT(sptam.t_m, kMaxStereoStepM) << k;
    EXPECT_LT(orb.r_deg, kMaxStereoStepDeg) << k;
    EXPECT_LT(sptam.r_deg, kMaxStereoStepDeg) << k;
    // Two LiDAR registrations (our features + Ceres; PCL GICP on 0.3 m voxels) agree more closely than the two
    // stereo references: measured <= 1.2 cm / 0.05 deg.
    EXPECT_LT(pcl.t_m, 0.02) << k;
    EXPECT_LT(pcl.r_deg, 0.1) << k;
    EXPECT_FALSE(r.degeneracy.degenerate) << k;  // an urban street observes all six directions
    if (k == 0) {
      // The official truth is wrong for frames 0..~13 of sequence 00 (a constant 0.86 m per frame): at 0->1 our
      // step is many times closer to both stereo references than to it (measured 17.6 cm vs <= 2.4 cm).
      EXPECT_GT(official.t_m, 4 * std::max(orb.t_m, sptam.t_m));
    }
    orb_m.push_back(orb.t_m);
    sptam_m.push_back(sptam.t_m);
    refs_m.push_back(refs.t_m);
    guess = ours;
  }
  std::printf("KITTI RMS over 10 steps: ours vs ORB-SLAM2 %.2f cm, vs S-PTAM %.2f cm; ORB vs S-PTAM %.2f cm\n",
              100 * Rms(orb_m), 100 * Rms(sptam_m), 100 * Rms(refs_m));
  EXPECT_LT(Rms(orb_m), Rms(refs_m));
  EXPECT_LT(Rms(sptam_m), Rms(refs_m));
}

TEST_F(Kitti00, SequentialOdometryThroughTheLocalMapAgreesWithDirectRegistration) {
  const LocalMap direct_map = SingleKeyframeMap(data_->features[0]);
  LocalMapConfig config;
  config.edge_voxel_m = 0.2;
  config.planar_voxel_m = 0.2;
  config.keyframe_distance_m = 1.0;  // frames 0, 2, 4 become keyframes at ~0.7 m per frame
  LocalMap map(config);
  map.AddKeyframe(data_->features[0], Pose3::Identity());
  std::vector<Pose3> odometry = {Pose3::Identity()};
  for (size_t k = 1; k <= 5; ++k) {
    const ScanToMapResult r = Register(data_->features[k], map, ConstantVelocityGuess(odometry), ScanToMapConfig());
    ASSERT_TRUE(r.converged) << "frame " << k << ": " << r.message;
    odometry.push_back(r.T_map_scan);
    if (map.NeedsKeyframe(r.T_map_scan)) map.AddKeyframe(data_->features[k], r.T_map_scan);
    const ScanToMapResult direct = Register(data_->features[k], direct_map, r.T_map_scan, ScanToMapConfig());
    const double dt = TranslationError(r.T_map_scan, direct.T_map_scan);
    const double dr = RotationErrorDeg(r.T_map_scan, direct.T_map_scan);
    std::printf("KITTI sequential 0->%zu (%zu keyframes): vs direct %.4f m %.4f deg\n", k, map.num_keyframes(), dt,
                dr);
    // Measured <= 5.6 mm / 0.017 deg: the keyframes' own registration errors enter the map.
    EXPECT_LT(dt, 0.02) << "frame " << k;
    EXPECT_LT(dr, 0.1) << "frame " << k;
  }
  EXPECT_EQ(map.num_keyframes(), 3u);
}

TEST(RegistrationRealData, GicpPairMatchesTheReferenceBothWays) {
  ROTOLIDAR_REQUIRE_DATA(data, "gicp_pair");
  const std::string dir = data + "/";
  Cloud target, source;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "251370668.pcd", target), 0) << dir << "251370668.pcd";
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "251371071.pcd", source), 0) << dir << "251371071.pcd";
  const std::vector<Pose3> fast = LoadPoses(dir + "relative.txt");
  const std::vector<Pose3> small = LoadPoses(dir + "T_target_source_small_gicp.txt");
  ASSERT_EQ(fast.size(), 1u) << dir << "relative.txt";
  ASSERT_EQ(small.size(), 1u) << dir << "T_target_source_small_gicp.txt";
  const PcaFeatureConfig pca;  // min_range_m also removes the ~5000 invalid points at (0, 0, 0)
  const FeatureSet f_target = PcaFeatures(target, pca), f_source = PcaFeatures(source, pca);
  const ScanToMapResult forward = Register(f_source, SingleKeyframeMap(f_target), Pose3::Identity(), {});
  const ScanToMapResult inverse = Register(f_target, SingleKeyframeMap(f_source), Pose3::Identity(), {});
  ASSERT_TRUE(forward.converged) << forward.message;
  ASSERT_TRUE(inverse.converged) << inverse.message;
  const Pose3 fwd = forward.T_map_scan, inv = inverse.T_map_scan.inverse();  // both as T_target_source
  std::printf("gicp_pair vs fast_gicp: forward %.4f m %.4f deg, inverse %.4f m %.4f deg\n",
              TranslationError(fwd, fast[0]), RotationErrorDeg(fwd, fast[0]), TranslationError(inv, fast[0]),
              RotationErrorDeg(inv, fast[0]));
  std::printf("gicp_pair vs small_gicp: forward %.4f m %.4f deg, inverse %.4f m %.4f deg (edge %d planar %d)\n",
              TranslationError(fwd, small[0]), RotationErrorDeg(fwd, small[0]), TranslationError(inv, small[0]),
              RotationErrorDeg(inv, small[0]), forward.edge_inliers, forward.planar_inliers);
  // fast_gicp's own test accepts 5 cm / 1 deg against its reference (itself another method's output; the two
  // references differ by 1.9 cm / 0.22 deg).
  for (const Pose3& ref : {fast[0], small[0]}) {
    EXPECT_LT(TranslationError(fwd, ref), 0.05);
    EXPECT_LT(RotationErrorDeg(fwd, ref), 1.0);
    EXPECT_LT(TranslationError(inv, ref), 0.05);
    EXPECT_LT(RotationErrorDeg(inv, ref), 1.0);
  }
}

}  // namespace
}  // namespace rotolidar
