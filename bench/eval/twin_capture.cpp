// Static captures of the VLP-16 twin (contract in twin_capture.hpp).
#include "bench/eval/twin_capture.hpp"

#include <cmath>
#include <memory>

#include "bench/eval/plane_residuals.hpp"
#include "core/wire/vlp16.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::bench {

Status CaptureTwinRevolutions(const TwinCaptureOptions& o, std::vector<LidarScan>* scans) {
  if (o.revolutions < 1) return Status::Error("twin capture: revolutions must be >= 1");
  if (o.lidar.return_mode == Vlp16ReturnMode::kDual) return Status::Error("twin capture: single return modes only");
  if (std::string why; !o.lidar.Validate(&why)) return Status::Error("twin capture: lidar." + why);
  std::string path;
  if (Status s = sim::FindSceneFile(o.scene, &path); !s) return s;
  sim::Scene scene;
  if (Status s = sim::LoadScene(path, &scene); !s) return s;
  std::unique_ptr<sim::EmbreeScene> embree;
  if (Status s = sim::EmbreeScene::Create(scene, &embree); !s) return s;
  if (Status s = sim::CheckCasterMaterials(o.lidar, embree->materials()); !s) return s;
  const LidarIntrinsics intrinsics;
  sim::Vlp16Caster caster(*embree, intrinsics, o.lidar, o.seed);
  const double revolution_s = 60.0 / o.lidar.rpm;
  const int sequences = static_cast<int>(std::ceil((o.revolutions + 2) * revolution_s / kVlp16SequencePeriodS));
  std::vector<Vlp16FiringSequence> sequences_out;
  caster.Fire(sequences, [&](Seconds) { return o.T_world_lidar; }, &sequences_out, nullptr);
  Vlp16PacketEncoder encoder(o.lidar.return_mode, 0.0);
  std::vector<LidarPacket> packets;
  for (const Vlp16FiringSequence& seq : sequences_out) {
    if (auto packet = encoder.Add(seq)) packets.push_back(std::move(*packet));
  }
  if (Status s = RevolutionsFromPackets(packets, intrinsics, scans); !s) return s;
  if (static_cast<int>(scans->size()) > o.revolutions) scans->resize(static_cast<std::size_t>(o.revolutions));
  return Status::Ok();
}

}  // namespace rotolidar::bench
