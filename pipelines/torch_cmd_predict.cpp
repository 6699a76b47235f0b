// `dvso predict --model model.pt (--images DIR | --sequence DIR) --out DIR
// [--post-process] [--device auto|cpu|cuda] [--no-color] [--threads N]`: writes
// left/NAME.png and right/NAME.png (KITTI uint16, disparity * 256, at the input
// image resolution; a disparity the PNG cannot hold, >= 256 px, is written as 0 =
// invalid) plus colour-mapped previews in left_color/ and right_color/.
// NAME: the input's file name with --images, the sequence's frame name with --sequence.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <future>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"
#include "core/progress.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "pipelines/commands.h"
#include "pipelines/prediction_source.h"
#include "stacknet/dataset.h"
#include "stacknet/predictor.h"

namespace dvso::cli {
namespace {
namespace fs = std::filesystem;

struct PredictArgs {
  std::string model, images, sequence, out, cameras;  // cameras "": per layout (see --cameras)
  stacknet::PredictorOptions options;
  bool no_color = false;
};

void RunPredict(const PredictArgs& args) {
  Require(args.images.empty() != args.sequence.empty(), "give exactly one of --images DIR or --sequence DIR");
  // A folder of images has no camera pairs to choose from: the option would be silently ignored.
  Require(args.cameras.empty() || !args.sequence.empty(), "--cameras needs --sequence");
  stacknet::PredictorOptions options = args.options;
  // The network leaves one core to the reader and writer threads: an OpenMP
  // team as large as the machine stalls at its barriers whenever an I/O thread
  // takes a core (measured: 854 ms/frame with 2 threads vs 112 ms with 1 on 2 cores).
  if (options.num_threads == 0)
    options.num_threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  stacknet::TorchDisparityPredictor predictor(args.model, options);
  std::cout << "Model " << args.model << " (network input " << predictor.input_width() << "x"
            << predictor.input_height() << ")" << (args.options.post_process ? ", post-processing on" : "") << "\n";
  std::unique_ptr<SequenceReader> sequence;
  std::string cameras;  // the pair the maps belong to (--sequence only), recorded for `odometry` to check
  std::vector<std::string> files;
  if (!args.sequence.empty()) {
    // By default the network sees the pair it trains on (stacknet::TrainingCameraPair: colour on a KITTI raw
    // drive, the pair `odometry` reads by default elsewhere, so that the maps sit on the tracked pixels).
    const CameraPair pair =
        !args.cameras.empty() ? ParseCameraPair(args.cameras) : stacknet::TrainingCameraPair(args.sequence);
    sequence = OpenSequence(args.sequence, "", pair);
    cameras = CameraPairName(sequence->camera_pair());  // the pair read (colour where there is no grey)
  } else {
    // The sequence readers' own listing, so that `odometry --sequence` over the same images (e.g. a KITTI
    // image_0/) finds a map for every frame it reads: a rule of predict's own skipped some of them.
    files = internal::ListImages(args.images);
    RequireFile(!files.empty(), args.images, "no images (.png/.jpg/.jpeg/.pgm/.bmp, any case)");
    std::set<std::string> stems;
    for (const std::string& f : files)
      RequireFile(stems.insert(fs::path(f).stem().string()).second, f,
                  "two images share this name (outputs keep the input names)");
  }
  const int count = sequence ? sequence->size() : static_cast<int>(files.size());
  // Output folders only once the inputs are known to be usable (a typo leaves nothing behind).
  for (const char* sub : {"left", "right"}) EnsureDirectory(JoinPath(args.out, sub));
  // An earlier run's record of its camera pair goes before the first map is replaced (this run writes its
  // own at the end): a killed rerun must not leave it over a mix of maps.
  fs::remove(JoinPath(args.out, kPredictionInfoFile));
  if (!args.no_color) {
    for (const char* sub : {"left_color", "right_color"}) EnsureDirectory(JoinPath(args.out, sub));
  }
  auto read = [&](int i) {
    cv::Mat image;
    if (sequence) {
      SequenceReadOptions options;
      options.load_right = false;
      options.load_color = sequence->has_color();
      const StereoFrame frame = sequence->Read(i, options);
      image = frame.left_color.empty() ? frame.left : frame.left_color;
    } else {
      // As the sequence readers (and `odometry --sequence` on the same files) see it: they ignore a JPEG's
      // EXIF orientation, so a map of the rotated image would not lie on the frame the odometry tracks.
      image = cv::imread(files[i], cv::IMREAD_COLOR | cv::IMREAD_IGNORE_ORIENTATION);
      RequireFile(!image.empty(), files[i], "cannot read image");
    }
    return image;
  };
  std::atomic<bool> removed_previews{false};  // --no-color removed a stale preview (set on the writer thread)
  std::atomic<long long> beyond_png_range{0};   // pixels made invalid by InvalidBeyondKittiMapRange (writer thread)
  std::atomic<long long> map_pixels{0};         // all pixels of the maps written
  auto write = [&](const DisparityPair& pair, const std::string& name) {
    // The network outputs up to 0.3 * width px, more than a KITTI PNG holds (255.996 px) on wide images:
    // WriteKittiMapPng would clamp such a disparity, i.e. write a wrong, too far depth. Invalid (0) instead,
    // as the simulator does for its ground truth.
    for (const cv::Mat* map : {&pair.left, &pair.right}) {
      beyond_png_range += cv::countNonZero(*map > kKittiMapMaxValue);
      map_pixels += static_cast<long long>(map->total());
    }
    WriteKittiMapPng(JoinPath(JoinPath(args.out, "left"), name), InvalidBeyondKittiMapRange(pair.left));
    WriteKittiMapPng(JoinPath(JoinPath(args.out, "right"), name), InvalidBeyondKittiMapRange(pair.right));
    if (!args.no_color) {
      // Like the maps: a full disk is an error, and a killed run never leaves a truncated preview in place.
      for (const bool left : {true, false}) {
        const std::string path = JoinPath(JoinPath(args.out, left ? "left_color" : "right_color"), name);
        const cv::Mat preview = stacknet::ColorizeDisparity(left ? pair.left : pair.right);
        WriteImageAtomically(path, preview);
      }
    } else {
      // A preview of this name from an earlier run no longer shows this map: remove it, not leave it beside.
      for (const char* sub : {"left_color", "right_color"}) {
        const std::string preview = JoinPath(JoinPath(args.out, sub), name);
        std::error_code error;
        if (fs::remove(preview, error)) removed_previews = true;
        RequireFile(!error, preview, "cannot remove the preview of an earlier run: " + error.message());
      }
    }
  };
  // Reading frame i + 1 and writing frame i - 1 run on two I/O threads while
  // the network predicts frame i; OpenCV stays single-threaded so that its
  // own worker threads do not compete with the network's on small machines.
  cv::setNumThreads(1);
  using Clock = std::chrono::steady_clock;
  double wait_read_s = 0, forward_s = 0, wait_write_s = 0;
  const auto start = Clock::now();
  std::future<cv::Mat> next = std::async(std::launch::async, read, 0);
  std::future<void> writing;
  ProgressBar progress("predict", count);
  for (int i = 0; i < count; ++i) {
    auto t0 = Clock::now();
    const cv::Mat image = next.get();
    if (i + 1 < count) next = std::async(std::launch::async, read, i + 1);
    auto t1 = Clock::now();
    DisparityPair pair = predictor.PredictImage(image);
    auto t2 = Clock::now();
    if (writing.valid()) writing.get();
    auto t3 = Clock::now();
    // --images keeps each input's name (as .png); --sequence numbers the frames.
    // Named like the frames, so the folders feed `odometry --mode dvso --disparity-left/-right` directly.
    std::string name = sequence ? sequence->FrameName(i) + ".png" : fs::path(files[i]).stem().string() + ".png";
    writing = std::async(std::launch::async, [&write, pair = std::move(pair), name = std::move(name)] { write(pair, name); });
    wait_read_s += std::chrono::duration<double>(t1 - t0).count();
    forward_s += std::chrono::duration<double>(t2 - t1).count();
    wait_write_s += std::chrono::duration<double>(t3 - t2).count();
    progress.Update(i + 1);
  }
  if (writing.valid()) writing.get();
  if (removed_previews) {
    // Preview folders this run emptied go too (a folder with other files stays).
    for (const char* sub : {"left_color", "right_color"}) {
      const std::string dir = JoinPath(args.out, sub);
      std::error_code ignored;
      if (fs::is_directory(dir, ignored) && fs::is_empty(dir, ignored)) fs::remove(dir, ignored);
    }
  }
  progress.Finish();
  const double total_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::cout << "Timing: " << count / std::max(total_s, 1e-9) << " frames/s; per frame " << 1000 * forward_s / count
            << " ms network (resize, forward, resize back), waiting " << 1000 * wait_read_s / count << " ms for reading and "
            << 1000 * wait_write_s / count << " ms for writing\n";
  if (beyond_png_range > 0) {
    std::cerr << "dvso: warning: dropped " << beyond_png_range.load() << " of " << map_pixels.load()
              << " predicted disparities beyond the KITTI PNG range (" << kKittiMapMaxValue
              << " px): written as invalid (0)" << std::endl;
  }
  // The model's metadata: `odometry --disparity-left` takes b_v from it, as when the model runs online. Which
  // pair the maps were predicted on: it checks that against the pair it reads (a raw drive's colour maps on its
  // grey images sit ~6 cm off); a folder of images has no pair.
  nlohmann::json info{{"model", args.model}, {"model_metadata", nlohmann::json::parse(predictor.metadata().ToJson())}};
  if (!cameras.empty()) {
    info["sequence"] = args.sequence;
    info["cameras"] = cameras;
  }
  WriteStreamAtomically(JoinPath(args.out, kPredictionInfoFile),
                        [&](std::ostream& out) { out << info.dump(2) << "\n"; });
  std::cout << "Wrote " << count << " left/right disparity maps to " << args.out << std::endl;
}

}  // namespace

void AddPredictCommand(CLI::App& app) {
  auto args = std::make_shared<PredictArgs>();
  auto* cmd = app.add_subcommand("predict", "Predict left/right disparity maps with an exported model");
  cmd->add_option("--model", args->model, "TorchScript model from `dvso export`")->required()->check(CLI::ExistingFile);
  cmd->add_option("--images", args->images,
                  "Folder of .png/.jpg/.jpeg/.pgm/.bmp images (any case, as the sequence readers list them); each "
                  "output keeps its input's name (as .png)");
  cmd->add_option("--sequence", args->sequence,
                  "Sequence folder (KITTI odometry layout / dvso simulate output / KITTI raw drive); outputs are "
                  "named like its frames");
  cmd->add_option("--cameras", args->cameras,
                  "KITTI layouts: colour (02/03) or grey (00/01) pair; default colour on raw drives (what the network "
                  "trained on), grey on odometry folders (what odometry reads by default; colour images are used when "
                  "they come from the grey cameras, as in simulated sequences). Odometry using these predictions must "
                  "read the same pair (odometry --cameras)");
  cmd->add_option("--out", args->out, "Output folder")->required();
  cmd->add_flag("--post-process", args->options.post_process, "Godard's flip-and-blend post-processing (left)");
  cmd->add_option("--device", args->options.device, "auto, cpu or cuda");
  cmd->add_flag("--no-color", args->no_color, "Skip the colour-mapped previews");
  cmd->add_option("--threads", args->options.num_threads, "CPU threads of the network (0 = all cores but one, which reads and writes)")
      ->capture_default_str();
  cmd->callback([args] { RunPredict(*args); });
}

}  // namespace dvso::cli
