#pragma once
// Keyframe database for visual place recognition (stage 1 of LV-SLAM's loop closure, Sensors 2025, Sec. 3.4):
// BoW vectors of past keyframes behind an inverted index (word -> keyframes holding it), queried with DBoW2's L1
// score (Galvez-Lopez & Tardos, T-RO 2012, Sec. IV-V) and filtered by its normalised similarity
//
//   eta(v_t, v_j) = s(v_t, v_j) / s(v_t, v_{t-1}),
//
// the raw score of candidate j divided by the score between the query and the previous keyframe: the best score
// this place can expect, which varies a lot from scene to scene. The seed accepts eta >= 0.35.
//
// Thread-safety: Add and Clear modify; the const queries may run concurrently with each other, not with Add.
// Failures are returned as Status; nothing throws.
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/loop/vocabulary.hpp"
#include "core/util/status.hpp"

namespace rotolidar::loop {

using KeyframeId = int64_t;  ///< the caller's keyframe number; unique within a database

/// One database hit.
struct BowCandidate {
  KeyframeId id = 0;
  double t_s = 0.0;               ///< the keyframe's time [s]
  double score = 0.0;             ///< raw L1 score s(v_query, v_candidate) in [0, 1]
  double normalised_score = 0.0;  ///< eta = score / s(v_query, v_previous); 0 where not computed (Query)
};

/// The acceptance rule of DetectLoop.
struct LoopQueryConfig {
  /// Keyframes newer than t_query - exclude_recent_s [s] are not candidates: they show the current place, not a
  /// loop. 20 s keeps the twin's box_room loop (20 s period) detectable; a forward-looking camera walked straight
  /// at 1.2 m/s (park, tunnel, clean_street) still matches its view of 20-25 s before (the same street ahead), so
  /// set it from the rig's speed and view, and let stage 2 (geometry) reject what is not a loop.
  double exclude_recent_s = 20.0;
  /// eta threshold: the seed's 0.35.
  double min_normalised_score = 0.35;
  /// Raw-score floor: a candidate with s below it is rejected whatever its eta, so that a small s(v_t, v_{t-1})
  /// cannot inflate a chance overlap into a large eta. Set it above the chance score of the vocabulary: with the
  /// shipped one (scenes/vocabulary/) images of different twin scenes score 0.000 median, 0.014 at the 90th
  /// percentile; views of one place after a small motion ~0.15-0.3.
  double min_raw_score = 0.03;
  /// When s(v_t, v_{t-1}) is below this the query is skipped (outcome kLowPreviousScore): eta would divide by a
  /// near-zero score, e.g. after a camera blackout or a sudden view change. DLoopDetector's min_nss_factor (0.005).
  double min_previous_score = 0.005;
  /// How many raw-score top candidates are considered before the eta filter.
  int max_results = 10;

  bool Validate(std::string* error) const;
};

/// What DetectLoop found and why.
struct LoopQueryResult {
  enum class Outcome {
    kAccepted,            ///< at least one candidate passed both thresholds
    kNoneAccepted,        ///< candidates were scored, none passed
    kNoPreviousKeyframe,  ///< no keyframe before t_query: eta is undefined, query skipped
    kLowPreviousScore,    ///< s(v_t, v_{t-1}) < min_previous_score: query skipped
    kEmptyQuery,          ///< the query vector has no word
  };
  Outcome outcome = Outcome::kEmptyQuery;
  KeyframeId previous_id = -1;     ///< the keyframe used as v_{t-1} (-1 when none)
  double previous_score = 0.0;     ///< s(v_t, v_{t-1})
  std::vector<BowCandidate> considered;  ///< top max_results by raw score (eta filled in), best first
  std::vector<BowCandidate> accepted;    ///< those passing both thresholds, by eta, best first
};

/// Name of an outcome, for logs ("accepted", "low_previous_score", ...).
const char* OutcomeName(LoopQueryResult::Outcome outcome);

class BowDatabase {
 public:
  /// Adds a keyframe. Times must strictly increase from one Add to the next and ids must be unique (both errors
  /// name the id and time); a non-finite time or a negative weight is an error. The vector is stored
  /// L1-normalised (an empty one is kept and never matches). Memory: ~32 bytes per word of each keyframe (its
  /// vector and the inverted index), e.g. ~10 kB for a twin image's ~320 words.
  Status Add(KeyframeId id, double t_s, const BowVector& bow);

  /// Raw-score retrieval through the inverted index: the at most max_results keyframes with t_s <= max_t_s
  /// sharing a word with `bow` (weights >= 0), by score descending (ties: older first). normalised_score is 0.
  std::vector<BowCandidate> Query(const BowVector& bow, size_t max_results, double max_t_s) const;

  /// The loop test for a keyframe at t_query_s: candidates are keyframes with t_s <= t_query_s -
  /// config.exclude_recent_s; v_{t-1} is the newest keyframe with t_s < t_query_s (usually the last one added;
  /// the query keyframe itself may already be in the database). Requires a valid config (Validate).
  LoopQueryResult DetectLoop(const BowVector& bow, double t_query_s, const LoopQueryConfig& config) const;

  size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  /// Copies the stored (L1-normalised) vector of a keyframe into *bow; false when the id is unknown.
  bool Find(KeyframeId id, BowVector* bow) const;
  void Clear();

 private:
  using SparseWords = std::vector<std::pair<WordId, double>>;  ///< by word; 16 bytes a word (a map node is ~48)
  struct Entry {
    KeyframeId id;
    double t_s;
    SparseWords words;  ///< L1-normalised
  };
  /// s(query, entry) as Vocabulary::Score, for a stored entry.
  static double ScoreEntry(const BowVector& query, const SparseWords& entry);
  struct Posting {
    uint32_t entry;  ///< index into entries_
    double weight;   ///< the word's weight in that entry
  };
  std::vector<Entry> entries_;  ///< in time order
  std::unordered_map<WordId, std::vector<Posting>> inverted_;
  std::unordered_map<KeyframeId, uint32_t> by_id_;
};

}  // namespace rotolidar::loop
