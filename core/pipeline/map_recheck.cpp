#include "core/pipeline/map_recheck.hpp"

#include <string>

#include "core/util/log.hpp"

namespace rotolidar {

MapRecheck::MapRecheck(const FreeSpaceConfig& config) : config_(config) {
  std::string why;
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
}

void MapRecheck::Track(Seconds t_s, const VoxelMap& map, const std::vector<size_t>& index) {
  if (index.empty()) return;
  Batch batch{t_s, Eigen::Matrix3Xf(3, Eigen::Index(index.size())), index, std::vector<uint8_t>(index.size(), 0)};
  for (size_t i = 0; i < index.size(); ++i) batch.p_world.col(Eigen::Index(i)) = map.Point(index[i]).cast<float>();
  tracked_ += index.size();
  batches_.push_back(std::move(batch));
}

// A hit resets a point's run (something is still there); a look through it extends the run. Unknown verdicts
// (not looked at, occluded, beyond recheck_max_range_m) leave it as it was.
void MapRecheck::Vote(Seconds t_s, const PlacedImage& image, std::vector<size_t>* remove) {
  while (!batches_.empty() && batches_.front().t_s < t_s - config_.recheck_s) {
    tracked_ -= batches_.front().index.size();
    batches_.pop_front();
  }
  if (image.image == nullptr || calls_++ % size_t(config_.vote_every_scans) != 0) return;
  const uint8_t needed = uint8_t(config_.recheck_min_through);
  for (Batch& batch : batches_) {
    JudgePoints(image, batch.p_world, float(config_.margin_m), float(config_.margin_per_m),
                float(config_.recheck_max_range_m), [&](size_t i, RangeImage::Verdict verdict) {
                  uint8_t& run = batch.run[i];
                  if (run == kRemoved) return;
                  if (verdict == RangeImage::Verdict::kHit) {
                    run = 0;
                  } else if (++run >= needed) {
                    run = kRemoved;
                    remove->push_back(batch.index[i]);
                  }
                });
  }
}

}  // namespace rotolidar
