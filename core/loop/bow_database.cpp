#include "core/loop/bow_database.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/validation.hpp"

namespace rotolidar::loop {
namespace {

// Best first by `key`; ties go to the older keyframe so results do not depend on container order.
template <typename Key>
void SortBest(std::vector<BowCandidate>* candidates, Key key) {
  std::sort(candidates->begin(), candidates->end(), [&](const BowCandidate& a, const BowCandidate& b) {
    return key(a) != key(b) ? key(a) > key(b) : a.t_s < b.t_s;
  });
}

}  // namespace

bool LoopQueryConfig::Validate(std::string* error) const {
  if (!std::isfinite(exclude_recent_s) || exclude_recent_s < 0.0)
    return FailValidation(error, "loop_query.exclude_recent_s: must be finite and >= 0");
  if (!(min_normalised_score >= 0.0) || !std::isfinite(min_normalised_score))
    return FailValidation(error, "loop_query.min_normalised_score: must be finite and >= 0");
  if (!(min_raw_score >= 0.0 && min_raw_score <= 1.0))
    return FailValidation(error, "loop_query.min_raw_score: must be in [0, 1]");
  if (!(min_previous_score > 0.0 && min_previous_score <= 1.0))
    return FailValidation(error, "loop_query.min_previous_score: must be in (0, 1]");
  if (max_results < 1) return FailValidation(error, "loop_query.max_results: must be >= 1");
  return true;
}

const char* OutcomeName(LoopQueryResult::Outcome outcome) {
  switch (outcome) {
    case LoopQueryResult::Outcome::kAccepted: return "accepted";
    case LoopQueryResult::Outcome::kNoneAccepted: return "none_accepted";
    case LoopQueryResult::Outcome::kNoPreviousKeyframe: return "no_previous_keyframe";
    case LoopQueryResult::Outcome::kLowPreviousScore: return "low_previous_score";
    case LoopQueryResult::Outcome::kEmptyQuery: return "empty_query";
  }
  return "unknown";
}

Status BowDatabase::Add(KeyframeId id, double t_s, const BowVector& bow) {
  const std::string what = "BoW database: keyframe " + std::to_string(id) + " at t_s " + std::to_string(t_s);
  if (!std::isfinite(t_s)) return Status::Error(what + ": time is not finite");
  if (by_id_.count(id)) return Status::Error(what + ": id already in the database");
  if (!entries_.empty() && !(t_s > entries_.back().t_s))
    return Status::Error(what + ": not after the last keyframe (t_s " + std::to_string(entries_.back().t_s) + ")");
  double sum = 0.0;
  for (const auto& [word, weight] : bow) {
    if (!std::isfinite(weight) || weight < 0.0) return Status::Error(what + ": word " + std::to_string(word) +
                                                                     " has a negative or non-finite weight");
    sum += weight;
  }
  Entry entry{id, t_s, {}};
  const uint32_t index = uint32_t(entries_.size());
  for (const auto& [word, weight] : bow) {
    if (weight <= 0.0) continue;
    entry.words.emplace_back(word, weight / sum);
    inverted_[word].push_back({index, weight / sum});
  }
  entries_.push_back(std::move(entry));
  by_id_[id] = index;
  return Status::Ok();
}

std::vector<BowCandidate> BowDatabase::Query(const BowVector& bow, size_t max_results, double max_t_s) const {
  // Entries are in time order, so the eligible ones are a prefix and every posting list can stop at its end.
  const auto end = std::upper_bound(entries_.begin(), entries_.end(), max_t_s,
                                    [](double t, const Entry& e) { return t < e.t_s; });
  const uint32_t limit = uint32_t(end - entries_.begin());
  double norm = 0.0;
  for (const auto& [word, weight] : bow) norm += std::abs(weight);
  if (limit == 0 || !(norm > 0.0) || max_results == 0) return {};
  // DBoW2's L1 scoring through the inverted index: only common words change ||a - b||_1 from 2, by
  // |x - y| - |x| - |y| each; s = -0.5 * (sum of those changes).
  std::vector<double> change(limit, 0.0);
  std::vector<uint32_t> touched;
  for (const auto& [word, weight] : bow) {
    const auto it = inverted_.find(word);
    if (it == inverted_.end()) continue;
    const double x = weight / norm;
    if (!(x > 0.0)) continue;
    for (const Posting& p : it->second) {
      if (p.entry >= limit) break;
      if (change[p.entry] == 0.0) touched.push_back(p.entry);
      change[p.entry] += std::abs(x - p.weight) - x - p.weight;
    }
  }
  std::vector<BowCandidate> candidates;
  candidates.reserve(touched.size());
  for (uint32_t e : touched) {
    const double score = -0.5 * change[e];
    candidates.push_back({entries_[e].id, entries_[e].t_s, score > 0.0 ? std::min(score, 1.0) : 0.0, 0.0});
  }
  SortBest(&candidates, [](const BowCandidate& c) { return c.score; });
  if (candidates.size() > max_results) candidates.resize(max_results);
  return candidates;
}

LoopQueryResult BowDatabase::DetectLoop(const BowVector& bow, double t_query_s, const LoopQueryConfig& config) const {
  LoopQueryResult result;
  double norm = 0.0;
  for (const auto& [word, weight] : bow) norm += std::abs(weight);
  if (!(norm > 0.0)) return result;  // kEmptyQuery
  const auto previous = std::lower_bound(entries_.begin(), entries_.end(), t_query_s,
                                         [](const Entry& e, double t) { return e.t_s < t; });
  if (previous == entries_.begin()) {
    result.outcome = LoopQueryResult::Outcome::kNoPreviousKeyframe;
    return result;
  }
  const Entry& prev = *(previous - 1);
  result.previous_id = prev.id;
  result.previous_score = ScoreEntry(bow, prev.words);
  if (result.previous_score < config.min_previous_score) {
    result.outcome = LoopQueryResult::Outcome::kLowPreviousScore;
    return result;
  }
  result.considered = Query(bow, size_t(config.max_results), t_query_s - config.exclude_recent_s);
  for (BowCandidate& c : result.considered) {
    c.normalised_score = c.score / result.previous_score;
    if (c.normalised_score >= config.min_normalised_score && c.score >= config.min_raw_score)
      result.accepted.push_back(c);
  }
  SortBest(&result.accepted, [](const BowCandidate& c) { return c.normalised_score; });
  result.outcome = result.accepted.empty() ? LoopQueryResult::Outcome::kNoneAccepted
                                           : LoopQueryResult::Outcome::kAccepted;
  return result;
}

bool BowDatabase::Find(KeyframeId id, BowVector* bow) const {
  bow->clear();
  const auto it = by_id_.find(id);
  if (it == by_id_.end()) return false;
  bow->insert(entries_[it->second].words.begin(), entries_[it->second].words.end());
  return true;
}

double BowDatabase::ScoreEntry(const BowVector& query, const SparseWords& entry) {
  double norm = 0.0;
  for (const auto& [word, weight] : query) norm += std::abs(weight);
  if (!(norm > 0.0) || entry.empty()) return 0.0;
  double change = 0.0;  // as in Vocabulary::Score; the entry is already L1-normalised
  auto iq = query.begin();
  auto ie = entry.begin();
  while (iq != query.end() && ie != entry.end()) {
    if (iq->first < ie->first) {
      ++iq;
    } else if (ie->first < iq->first) {
      ++ie;
    } else {
      const double x = iq->second / norm;
      change += std::abs(x - ie->second) - std::abs(x) - ie->second;
      ++iq, ++ie;
    }
  }
  const double score = -0.5 * change;
  return score > 0.0 ? std::min(score, 1.0) : 0.0;
}

void BowDatabase::Clear() {
  entries_.clear();
  inverted_.clear();
  by_id_.clear();
}

}  // namespace rotolidar::loop
