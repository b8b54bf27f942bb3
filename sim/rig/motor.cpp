#include "sim/rig/motor.hpp"

#include <cmath>
#include <sstream>

#include "core/util/log.hpp"

namespace rotolidar::sim {

bool EncoderConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "EncoderConfig: " + m;
    return false;
  };
  if (counts_per_rev < 4) return fail("counts_per_rev must be >= 4");
  if (!std::isfinite(noise_sigma_counts) || noise_sigma_counts < 0)
    return fail("noise_sigma_counts must be finite and >= 0");
  if (!std::isfinite(latency_s) || latency_s < 0) return fail("latency_s must be finite and >= 0");
  if (!std::isfinite(rate_hz) || rate_hz <= 0) return fail("rate_hz must be finite and > 0");
  if (!std::isfinite(zero_offset_rad)) return fail("zero_offset_rad must be finite");
  return true;
}

EncoderCalib EncoderConfig::ToCalib() const {
  EncoderCalib calib;
  calib.counts_per_rev = counts_per_rev;
  calib.zero_offset_rad = zero_offset_rad;
  calib.rate_hz = rate_hz;
  return calib;
}

EncoderModel::EncoderModel(const EncoderConfig& config, uint64_t run_seed)
    : config_(config), noise_(run_seed, "encoder.noise") {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
}

uint32_t EncoderModel::Quantise(double raw_angle_rad, double noise_counts) const {
  const double cpr = static_cast<double>(config_.counts_per_rev);
  // Reduce the angle to one turn first so large unwrapped angles keep their sub-count precision.
  const double turn = raw_angle_rad / (2.0 * M_PI);
  const double frac = turn - std::floor(turn);  // [0, 1)
  const double counts = std::floor(frac * cpr + noise_counts);
  double wrapped = std::fmod(counts, cpr);
  if (wrapped < 0) wrapped += cpr;
  return static_cast<uint32_t>(wrapped) % config_.counts_per_rev;
}

EncoderSample EncoderModel::Sample(const RotorMotion& rotor, Seconds t) {
  return SampleAngle(t, rotor.AngleAt(t - config_.latency_s));
}

EncoderSample EncoderModel::SampleAngle(Seconds t, double theta_rad) {
  const double raw = theta_rad + config_.zero_offset_rad;
  const double noise = config_.noise_sigma_counts > 0 ? config_.noise_sigma_counts * noise_.Normal() : 0.0;
  return EncoderSample{t, Quantise(raw, noise)};
}

std::vector<EncoderSample> EncoderModel::SampleRange(const RotorMotion& rotor, Seconds t0, Seconds t1) {
  ROTOLIDAR_CHECK(t1 >= t0, "t0 " << t0 << " > t1 " << t1);
  const double dt = 1.0 / config_.rate_hz;
  const auto n = static_cast<long>(std::floor((t1 - t0) / dt + 1e-9));
  std::vector<EncoderSample> out;
  out.reserve(static_cast<size_t>(n + 1));
  for (long i = 0; i <= n; ++i) out.push_back(Sample(rotor, t0 + static_cast<double>(i) * dt));
  return out;
}

EncoderStream::EncoderStream(const EncoderConfig& config, uint64_t run_seed) : quantiser_(config, run_seed) {}

void EncoderStream::Push(const RotorJointState& state, std::vector<EncoderSample>* out) {
  ROTOLIDAR_CHECK(std::isfinite(state.t_s) && std::isfinite(state.theta_rad) && std::isfinite(state.omega_radps),
                  "non-finite rotor state at t " << state.t_s);
  ROTOLIDAR_CHECK(history_.empty() || state.t_s > history_.back().t_s,
                  "states must come in increasing time: " << state.t_s << " after " << history_.back().t_s);
  const EncoderConfig& c = quantiser_.config();
  const double period = 1.0 / c.rate_hz;
  if (!started_) {
    next_k_ = static_cast<int64_t>(std::ceil(state.t_s / period - 1e-9));
    started_ = true;
  }
  history_.push_back(state);
  for (;;) {
    const double t_k = static_cast<double>(next_k_) * period;
    if (t_k > state.t_s + 1e-9) break;
    out->push_back(quantiser_.SampleAngle(t_k, TrueAngleAt(t_k - c.latency_s)));
    ++next_k_;
  }
  // Keep what the next samples can still ask for: everything after (now - latency) plus the state before it.
  const double keep_after = state.t_s - c.latency_s - period;
  while (history_.size() > 2 && history_[1].t_s < keep_after) history_.pop_front();
}

double EncoderStream::TrueAngleAt(Seconds t) const {
  ROTOLIDAR_CHECK(!history_.empty(), "no state pushed yet");
  const RotorJointState& first = history_.front();
  if (t <= first.t_s) return first.theta_rad + first.omega_radps * (t - first.t_s);
  const RotorJointState& last = history_.back();
  if (t >= last.t_s) return last.theta_rad + last.omega_radps * (t - last.t_s);
  // The segment [a, b] holding t (history is short: a linear scan from the back is cheapest).
  size_t i = history_.size() - 1;
  while (history_[i - 1].t_s > t) --i;
  const RotorJointState& a = history_[i - 1];
  const RotorJointState& b = history_[i];
  const double h = b.t_s - a.t_s, s = (t - a.t_s) / h, s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * a.theta_rad + (s3 - 2 * s2 + s) * h * a.omega_radps +
         (-2 * s3 + 3 * s2) * b.theta_rad + (s3 - s2) * h * b.omega_radps;
}

}  // namespace rotolidar::sim
