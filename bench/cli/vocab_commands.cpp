// `rotolidar vocab train|info`: ORB bag-of-words vocabularies for the visual loop-closure stage
// (core/loop/vocabulary.hpp). train extracts ORB from images or recordings and builds the k-medians tree.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/run/progress.hpp"
#include "core/io/csv.hpp"
#include "core/io/recording.hpp"
#include "core/loop/orb_features.hpp"
#include "core/loop/vocabulary.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

bool IsImageFile(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// The camera frames of a recording folder, from camera.csv (core/io/recording.hpp's layout). Only camera.csv is
// read: LoadRecording would also load the whole lidar.pcap.
Status RecordingImages(const std::string& dir, std::vector<std::string>* paths) {
  CsvReader reader;
  const std::string csv = dir + "/" + RecordingLayout::kCamera;
  if (Status s = reader.Open(csv, {"t_s", "index"}); !s) return s;
  std::vector<double> row;
  while (reader.Next(&row)) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06ld.png", long(row[1]));
    paths->push_back(dir + "/" + RecordingLayout::kCameraDir + "/" + name);
  }
  return reader.status();
}

// The images of one input argument, in order: a recording folder (camera.csv), a folder of png/jpg files (sorted
// by name, not recursive) or one image file.
Status InputImages(const std::string& input, std::vector<std::string>* paths) {
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    if (fs::exists(fs::path(input) / RecordingLayout::kCamera)) return RecordingImages(input, paths);
    std::vector<std::string> found;
    for (const auto& entry : fs::directory_iterator(input, ec))
      if (entry.is_regular_file() && IsImageFile(entry.path())) found.push_back(entry.path().string());
    if (ec) return Status::Error(input + ": cannot list the folder: " + ec.message());
    if (found.empty()) return Status::Error(input + ": no camera.csv and no .png/.jpg images in this folder");
    std::sort(found.begin(), found.end());
    paths->insert(paths->end(), found.begin(), found.end());
    return Status::Ok();
  }
  if (fs::is_regular_file(input, ec) && IsImageFile(input)) {
    paths->push_back(input);
    return Status::Ok();
  }
  return Status::Error(input + ": not a recording folder, an image folder or a .png/.jpg file");
}

// ORB descriptors of every image (one matrix per image); fails on the first unreadable image.
Status ExtractAll(const std::vector<std::string>& images, const loop::OrbConfig& orb, std::vector<cv::Mat>* out) {
  loop::OrbExtractor extractor(orb);
  const auto progress = MakeProgressPrinter("orb");
  for (size_t i = 0; i < images.size(); ++i) {
    CameraFrame frame;
    if (Status s = LoadCameraFrame({0.0, images[i]}, &frame); !s) return s;
    loop::OrbFeatures features;
    if (Status s = extractor.Extract(frame.image, &features); !s) return Status::Error(images[i] + ": " + s.message);
    out->push_back(features.descriptors);
    progress(double(i + 1) / double(images.size()));
  }
  return Status::Ok();
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// A sanity check of the result: scores of neighbouring training images (usually views of one place) against
// those of images half the set apart (usually different places). A useful vocabulary separates them clearly.
void PrintSeparation(const loop::Vocabulary& vocabulary, const std::vector<cv::Mat>& descriptors) {
  std::vector<loop::BowVector> bows(descriptors.size());
  double words = 0.0;
  for (size_t i = 0; i < descriptors.size(); ++i) {
    (void)vocabulary.Transform(descriptors[i], &bows[i]);  // cannot fail: the training input was checked
    words += double(bows[i].size()) / double(descriptors.size());
  }
  std::vector<double> near, far;
  const size_t half = bows.size() / 2;
  for (size_t i = 0; i + 1 < bows.size(); ++i) near.push_back(loop::Vocabulary::Score(bows[i], bows[i + 1]));
  for (size_t i = 0; i + half < bows.size() && half > 1; ++i)
    far.push_back(loop::Vocabulary::Score(bows[i], bows[i + half]));
  std::printf("words per image %.0f; median score: neighbouring images %.3f, images half the set apart %.3f\n", words,
              Median(near), Median(far));
}

Status ParseTrainOptions(const OptionParser& p, loop::VocabularyConfig* config, loop::OrbConfig* orb, long* every) {
  long k = 0, levels = 0, features = 0, seed = 0, iterations = 0;
  for (const Status& s : {p.GetInt("k", &k), p.GetInt("levels", &levels), p.GetInt("features", &features),
                          p.GetInt("every", every), p.GetInt("seed", &seed), p.GetInt("iterations", &iterations)})
    if (!s) return s;
  if (*every < 1) return Status::Error("vocab train: --every must be >= 1");
  if (seed < 0) return Status::Error("vocab train: --seed must be >= 0");
  config->branching = int(std::clamp(k, -1L, 1L << 20));
  config->depth = int(std::clamp(levels, -1L, 1L << 20));
  config->max_iterations = int(std::clamp(iterations, -1L, 1L << 20));
  config->seed = uint64_t(seed);
  orb->max_features = int(std::clamp(features, -1L, 1L << 24));
  std::string why;
  if (!config->Validate(&why) || !orb->Validate(&why)) return Status::Error("vocab train: " + why);
  return Status::Ok();
}

// Splits argv into options (with their values) and input paths: OptionParser takes one positional per name, the
// inputs are any number. The first input stays with the options so that the parser reports a missing one.
void SplitInputs(int argc, char** argv, const std::set<std::string>& valued, std::vector<char*>* options,
                 std::vector<std::string>* inputs) {
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0 || arg == "-h") {
      options->push_back(argv[i]);
      if (arg.find('=') == std::string::npos && valued.count(arg.substr(2)) && i + 1 < argc)
        options->push_back(argv[++i]);
    } else if (inputs->empty()) {
      options->push_back(argv[i]);
      inputs->push_back(arg);
    } else {
      inputs->push_back(arg);
    }
  }
}

int VocabTrain(int argc, char** argv) {
  const loop::VocabularyConfig d;
  OptionParser p("vocab train", "Train an ORB bag-of-words vocabulary (DBoW2-style k-medians tree, TF-IDF weights) "
                                "from images or recordings and save it. Nothing is written when a step fails.");
  p.AddPositional("INPUTS...", "recording folders (camera.csv + camera/), folders of .png/.jpg images, or images");
  p.Add("out", "", "-", "vocabulary file to write (required)");
  p.Add("k", std::to_string(d.branching), "-", "branching factor: children per tree node");
  p.Add("levels", std::to_string(d.depth), "-", "tree depth: at most k^levels words");
  p.Add("features", std::to_string(loop::OrbConfig().max_features), "-", "ORB features per image (at most)");
  p.Add("every", "1", "-", "use every N-th image of each input (the first included)");
  p.Add("seed", std::to_string(d.seed), "-", "random seed of the k-means++ seeding");
  p.Add("iterations", std::to_string(d.max_iterations), "-", "k-majority rounds per node (at most)");
  std::vector<char*> options;
  std::vector<std::string> inputs;
  SplitInputs(argc, argv, {"out", "k", "levels", "features", "every", "seed", "iterations"}, &options, &inputs);
  if (int rc = ParseOrHelp(p, int(options.size()), options.data()); rc >= 0) return rc;
  if (p.Get("out").empty()) return Usage("vocab train: --out is required");
  loop::VocabularyConfig config;
  loop::OrbConfig orb;
  long every = 1;
  if (Status s = ParseTrainOptions(p, &config, &orb, &every); !s) return Usage(s.message);

  std::vector<std::string> images;
  for (const std::string& input : inputs) {
    std::vector<std::string> all;
    if (Status s = InputImages(input, &all); !s) return Fail(s);
    for (size_t i = 0; i < all.size(); i += size_t(every)) images.push_back(all[i]);
  }
  std::printf("%zu images from %zu inputs (every %ld of each)\n", images.size(), inputs.size(), every);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<cv::Mat> descriptors;
  if (Status s = ExtractAll(images, orb, &descriptors); !s) return Fail(s);
  const auto t1 = std::chrono::steady_clock::now();
  loop::Vocabulary vocabulary;
  loop::VocabularyTrainStats stats;
  if (Status s = vocabulary.Train(descriptors, config, &stats, MakeProgressPrinter("train")); !s) return Fail(s);
  const auto t2 = std::chrono::steady_clock::now();
  if (Status s = vocabulary.Save(p.Get("out")); !s) return Fail(s);
  const double orb_s = std::chrono::duration<double>(t1 - t0).count();
  const double train_s = std::chrono::duration<double>(t2 - t1).count();
  std::printf("%zu descriptors from %zu images (ORB %.1f s) -> %zu words, %zu nodes, %zu unreached (k %d, L %d, "
              "train %.1f s)\n", stats.num_descriptors, stats.num_images, orb_s, stats.num_words, stats.num_nodes,
              stats.unreached_words, config.branching, config.depth, train_s);
  PrintSeparation(vocabulary, descriptors);
  std::printf("wrote %s (%ju bytes)\n", p.Get("out").c_str(), uintmax_t(fs::file_size(p.Get("out"))));
  return 0;
}

int VocabInfo(int argc, char** argv) {
  OptionParser p("vocab info", "Load a vocabulary file (checking it) and print its shape and weights.");
  p.AddPositional("FILE", "vocabulary file written by `rotolidar vocab train`");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  loop::Vocabulary v;
  if (Status s = v.Load(p.Get("FILE")); !s) return Fail(s);
  std::vector<double> weights;
  for (loop::WordId w = 0; w < v.num_words(); ++w) weights.push_back(v.WordWeight(w));
  std::sort(weights.begin(), weights.end());
  std::printf("%s: k %d, L %d, %zu words, %zu nodes, trained on %ju images; IDF weight min %.3f median %.3f max "
              "%.3f\n", p.Get("FILE").c_str(), v.branching(), v.depth(), v.num_words(), v.num_nodes(),
              uintmax_t(v.num_training_images()), weights.front(), weights[weights.size() / 2], weights.back());
  return 0;
}

void PrintVocabUsage(std::ostream& os) {
  os << "usage: rotolidar vocab <train|info> [options]   (rotolidar vocab <sub> --help)\n"
     << "  train INPUTS... --out FILE   train a vocabulary on images or recordings' camera frames\n"
     << "  info FILE                    check a vocabulary file and print its shape\n";
}

}  // namespace

int CmdVocab(int argc, char** argv) {
  if (argc < 1 || std::string(argv[0]) == "--help" || std::string(argv[0]) == "-h") {
    PrintVocabUsage(argc < 1 ? std::cerr : std::cout);
    return argc < 1 ? 2 : 0;
  }
  const std::string sub = argv[0];
  if (sub == "train") return VocabTrain(argc - 1, argv + 1);
  if (sub == "info") return VocabInfo(argc - 1, argv + 1);
  std::cerr << "error: unknown vocab subcommand '" << sub << "'\n";
  PrintVocabUsage(std::cerr);
  return 2;
}

}  // namespace rotolidar::bench
