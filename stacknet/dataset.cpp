#include "stacknet/dataset.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/depth_split.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "stacknet/augmentation.h"

namespace dvso::stacknet {
namespace fs = std::filesystem;
namespace {

// cv::Mat (grey or BGR, 8 bit) -> 3 x H x W RGB float tensor in [0, 1] at width x height.
torch::Tensor ImageToTensor(const cv::Mat& image, int width, int height) {
  cv::Mat rgb;
  if (image.channels() == 1) {
    cv::cvtColor(image, rgb, cv::COLOR_GRAY2RGB);
  } else {
    cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
  }
  if (rgb.cols != width || rgb.rows != height) {
    cv::Mat resized;
    cv::resize(rgb, resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    rgb = resized;
  }
  cv::Mat as_float;
  rgb.convertTo(as_float, CV_32FC3, 1.0 / 255.0);
  return torch::from_blob(as_float.data, {height, width, 3}, torch::kFloat32).permute({2, 0, 1}).clone();
}

// Sparse map in pixels of the network width -> (label as width fraction, mask).
void LabelToTensors(const cv::Mat& label, int width, int height, torch::Tensor* value, torch::Tensor* mask) {
  if (label.empty()) {
    *value = torch::zeros({1, height, width});
    *mask = torch::zeros({1, height, width});
    return;
  }
  cv::Mat contiguous = label.clone();
  const torch::Tensor pixels = torch::from_blob(contiguous.data, {1, height, width}, torch::kFloat32).clone();
  *mask = (pixels > 0).to(torch::kFloat32);
  *value = pixels / static_cast<double>(width);
}

}  // namespace

cv::Mat ResizeSparseDisparity(const cv::Mat& sparse, int width, int height) {
  Require(sparse.type() == CV_32F, "ResizeSparseDisparity expects CV_32F");
  if (sparse.cols == width && sparse.rows == height) return sparse.clone();
  cv::Mat out = cv::Mat::zeros(height, width, CV_32F);
  const double sx = static_cast<double>(width) / sparse.cols;
  const double sy = static_cast<double>(height) / sparse.rows;
  for (int y = 0; y < sparse.rows; ++y) {
    const float* row = sparse.ptr<float>(y);
    for (int x = 0; x < sparse.cols; ++x) {
      if (!(row[x] > 0)) continue;
      // Pixel centres map as (x + 0.5) * s - 0.5; the nearest target pixel gets the label.
      const int tx = std::clamp(static_cast<int>(std::floor((x + 0.5) * sx)), 0, width - 1);
      const int ty = std::clamp(static_cast<int>(std::floor((y + 0.5) * sy)), 0, height - 1);
      out.at<float>(ty, tx) = static_cast<float>(row[x] * sx);
    }
  }
  return out;
}

cv::Mat SampleSparse(const cv::Mat& dense, double fraction, uint64_t seed) {
  cv::Mat out = cv::Mat::zeros(dense.size(), CV_32F);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int y = 0; y < dense.rows; ++y) {
    for (int x = 0; x < dense.cols; ++x) {
      const float v = dense.at<float>(y, x);
      if (v > 0 && uniform(rng) < fraction) out.at<float>(y, x) = v;
    }
  }
  return out;
}

CameraPair TrainingCameraPair(const std::string& root) {
  // The network learns from the colour pair of a raw drive (paper 5.1: KITTI raw, cameras 02/03).
  return IsKittiRawDrive(root) ? CameraPair::kColour : CameraPair::kGrey;
}

std::unique_ptr<SequenceReader> OpenTrainingSequence(const std::string& root) {
  return OpenSequence(root, "", TrainingCameraPair(root));
}

void RequireLabelsOfTrainingPair(const std::string& label_dir, CameraPair training_pair) {
  if (label_dir.empty()) return;
  const fs::path dir = NormalizedFolderPath(label_dir);  // a trailing slash must not move the parent
  for (const fs::path& summary : {dir / "labels_summary.json", dir.parent_path() / "labels_summary.json"}) {
    if (!fs::is_regular_file(summary)) continue;
    const std::optional<CameraPair> made = RecordedCameraPair(summary.string());
    const std::string want = CameraPairName(training_pair);
    RequireFile(!made || *made == training_pair, summary.string(),
                "these labels were made on the " + CameraPairName(made.value_or(training_pair)) +
                    " pair, training reads the " + want + " pair of this sequence: run `dvso labels --cameras " + want +
                    " --overwrite`");
    return;
  }
}

namespace {
// Folder of a split line's drive: absolute as written, else under split_root (default: the split file's folder).
std::string SplitDriveRoot(const DataOptions& options, const std::string& drive) {
  if (fs::path(drive).is_absolute()) return drive;
  const fs::path base =
      options.split_root.empty() ? fs::path(options.split_file).parent_path() : fs::path(options.split_root);
  return (base / drive).string();
}
}  // namespace

std::vector<std::string> TrainingSequenceRoots(const DataOptions& options) {
  if (options.split_file.empty()) return options.sequences;
  std::vector<std::string> roots;
  for (const SplitEntry& entry : ReadSplitFile(options.split_file)) {
    const std::string root = SplitDriveRoot(options, entry.drive);
    if (std::find(roots.begin(), roots.end(), root) == roots.end()) roots.push_back(root);
  }
  return roots;
}

StereoDataset::StereoDataset(const DataOptions& options, int network_width, int network_height)
    : options_(options), width_(network_width), height_(network_height) {
  options_.Check();
  if (!options_.split_file.empty()) {
    AddSplit(options_.split_file);
  } else {
    for (const auto& root : options_.sequences) {
      const int seq = AddSequence(root);
      for (int f = 0; f < sequences_[seq].reader->size(); f += options_.frame_step) items_.push_back({seq, f});
    }
  }
  Require(!items_.empty(), "dataset: no training frames found");
}

void StereoDataset::AddSplit(const std::string& split_file) {
  // Split frames are file numbers ("0000000069"); a reader's index differs from it where
  // cameras dropped frames (extract drives), so look the number up among the frame names.
  std::vector<std::map<long long, int>> index_of_number;
  for (const SplitEntry& entry : ReadSplitFile(split_file)) {
    const std::string root = SplitDriveRoot(options_, entry.drive);
    const int seq = AddSequence(root);
    if (static_cast<int>(index_of_number.size()) <= seq) index_of_number.resize(seq + 1);
    std::map<long long, int>& numbers = index_of_number[seq];
    if (numbers.empty()) {
      const SequenceReader& reader = *sequences_[seq].reader;
      for (int i = 0; i < reader.size(); ++i) {
        if (const std::optional<long long> number = ParseFrameNumber(reader.FrameName(i))) numbers[*number] = i;
      }
    }
    const auto found = numbers.find(entry.frame);
    RequireFile(found != numbers.end(), split_file,
                "frame " + entry.FrameName() + " of " + entry.drive + " is not a stereo pair of that sequence");
    items_.push_back({seq, found->second, entry.side == 'r'});
  }
}

int StereoDataset::AddSequence(const std::string& root) {
  for (size_t i = 0; i < sequences_.size(); ++i) {
    if (sequences_[i].root == root) return static_cast<int>(i);
  }
  Sequence seq;
  seq.root = root;
  RequireFile(fs::is_directory(root), root, "sequence folder not found");
  seq.reader = OpenTrainingSequence(root);
  RequireFile(seq.reader->is_stereo(), root, "training needs a stereo sequence: " + seq.reader->NotStereoReason());
  auto dir_if_exists = [&](const std::string& name) {
    if (name.empty()) return std::string();
    const std::string dir = fs::path(name).is_absolute() ? name : JoinPath(root, name);
    return fs::is_directory(dir) ? dir : std::string();
  };
  seq.left_labels = dir_if_exists(options_.label_dir_left);
  seq.right_labels = dir_if_exists(options_.label_dir_right);
  for (const std::string& labels : {seq.left_labels, seq.right_labels}) {
    RequireLabelsOfTrainingPair(labels, seq.reader->camera_pair());  // the pair read (colour where no grey)
  }
  if (seq.left_labels.empty() && seq.right_labels.empty()) {
    // Until Stereo DSO labels exist for this sequence: sparse samples of the simulator's GT.
    seq.left_labels = dir_if_exists(options_.gt_disparity_left);
    seq.right_labels = dir_if_exists(options_.gt_disparity_right);
    seq.labels_are_dense_gt = !seq.left_labels.empty() || !seq.right_labels.empty();
  }
  sequences_.push_back(std::move(seq));
  return static_cast<int>(sequences_.size()) - 1;
}

void StereoDataset::ReadImages(const Sequence& seq, int frame, cv::Mat* left, cv::Mat* right) const {
  RequireFile(frame < seq.reader->size(), seq.root, "frame " + std::to_string(frame) + " out of range");
  SequenceReadOptions read;
  read.load_color = options_.use_color && seq.reader->has_color();
  const StereoFrame f = seq.reader->Read(frame, read);
  const bool color = !f.left_color.empty() && !f.right_color.empty();
  *left = color ? f.left_color : f.left;
  *right = color ? f.right_color : f.right;
}

cv::Mat StereoDataset::ReadLabel(const Sequence& seq, const std::string& dir, int frame, int side) const {
  if (dir.empty()) return cv::Mat();
  const std::string path = JoinPath(dir, FrameFileName(frame, ".png"));
  if (!fs::exists(path)) return cv::Mat();  // frames without labels train self-supervised only
  cv::Mat label = ReadKittiMapPng(path);
  if (seq.labels_are_dense_gt) {
    // Fixed per frame (not per epoch), like a label file would be.
    const uint64_t seed = std::hash<std::string>{}(seq.root) ^ (static_cast<uint64_t>(frame) * 2654435761ULL + side);
    label = SampleSparse(label, options_.gt_sample_fraction, seed);
  }
  return ResizeSparseDisparity(label, width_, height_);
}

StereoSample StereoDataset::Load(int index) const {
  Require(index >= 0 && index < size(), "dataset index out of range");
  const Item& item = items_[index];
  const Sequence& seq = sequences_[item.sequence];
  cv::Mat left, right;
  ReadImages(seq, item.frame, &left, &right);
  StereoSample s;
  s.left = ImageToTensor(left, width_, height_);
  s.right = ImageToTensor(right, width_, height_);
  LabelToTensors(ReadLabel(seq, seq.left_labels, item.frame, 0), width_, height_, &s.left_label, &s.left_mask);
  LabelToTensors(ReadLabel(seq, seq.right_labels, item.frame, 1), width_, height_, &s.right_label, &s.right_mask);
  return item.mirrored ? FlipAndSwap(s) : s;
}

std::string StereoDataset::Describe() const {
  std::ostringstream out;
  out << items_.size() << " stereo pairs from " << sequences_.size() << " sequence(s), network input " << width_
      << "x" << height_ << "\n";
  for (const auto& s : sequences_) {
    out << "  " << s.root << ": labels "
        << (s.left_labels.empty() && s.right_labels.empty()
                ? std::string("none (self-supervised only)")
                : (s.labels_are_dense_gt ? "sampled from GT " : "") + s.left_labels +
                      (s.right_labels.empty() ? "" : " | " + s.right_labels))
        << "\n";
  }
  return out.str();
}

}  // namespace dvso::stacknet
