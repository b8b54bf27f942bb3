// FeatureConfig::Validate names the field it rejects.
#include <gtest/gtest.h>

#include <string>

#include "core/features/curvature_features.hpp"

namespace rotolidar {
namespace {

TEST(FeatureConfig, ValidateNamesTheField) {
  std::string error;
  EXPECT_TRUE(FeatureConfig().Validate(&error)) << error;
  struct Case {
    const char* field;
    void (*breaks)(FeatureConfig*);
  };
  const Case cases[] = {
      {"features.sectors", [](FeatureConfig* c) { c->sectors = 0; }},
      {"features.edges_per_sector", [](FeatureConfig* c) { c->edges_per_sector = -1; }},
      {"features.planars_per_sector", [](FeatureConfig* c) { c->planars_per_sector = -1; }},
      {"features.less_sharp_per_sector", [](FeatureConfig* c) { c->less_sharp_per_sector = 3; }},
      {"features.neighbours", [](FeatureConfig* c) { c->neighbours = 0; }},
      {"features.edge_threshold", [](FeatureConfig* c) { c->edge_threshold = 0; }},
      {"features.planar_threshold", [](FeatureConfig* c) { c->planar_threshold = 0.1; }},
      {"features.max_neighbour_step_deg", [](FeatureConfig* c) { c->max_neighbour_step_deg = 0; }},
      {"features.occlusion_min_jump_m", [](FeatureConfig* c) { c->occlusion_min_jump_m = -1; }},
      {"features.occlusion_jump_ratio", [](FeatureConfig* c) { c->occlusion_jump_ratio = -1; }},
      {"features.beam_parallel_max_incidence_deg",
       [](FeatureConfig* c) { c->beam_parallel_max_incidence_deg = 90; }},
      {"features.range_sigma_m", [](FeatureConfig* c) { c->range_sigma_m = -0.01; }},
      {"features.edge_min_snr", [](FeatureConfig* c) { c->edge_min_snr = -1; }},
      {"features.planar_voxel_m", [](FeatureConfig* c) { c->planar_voxel_m = -1; }},
      {"features.less_flat_voxel_m", [](FeatureConfig* c) { c->less_flat_voxel_m = -1; }},
      {"features.threads", [](FeatureConfig* c) { c->threads = -1; }},
  };
  for (const Case& c : cases) {
    FeatureConfig config;
    c.breaks(&config);
    error.clear();
    EXPECT_FALSE(config.Validate(&error)) << c.field;
    EXPECT_NE(error.find(c.field), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace rotolidar
