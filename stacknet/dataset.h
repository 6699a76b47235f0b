// Stereo training samples: pairs from the core sequence readers (KITTI
// odometry layout, `dvso simulate` output, KITTI raw drives with image_02/
// image_03), sparse disparity labels, resizing to the network size.
#pragma once

#include <torch/torch.h>

#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/sequence.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// One sample at network resolution, before batching.
struct StereoSample {
  torch::Tensor left, right;              // 3 x H x W, RGB in [0, 1]
  torch::Tensor left_label, right_label;  // 1 x H x W, fraction of the width
  torch::Tensor left_mask, right_mask;    // 1 x H x W, 1 = labelled
};

// Resizes a sparse disparity map (pixels, 0 = none) to width x height without
// smearing: every labelled pixel moves to its scaled position and its value
// scales with the width (nearest, no interpolation between labels).
cv::Mat ResizeSparseDisparity(const cv::Mat& sparse, int width, int height);

// Keeps a random `fraction` of the valid pixels of a dense map (simulator GT)
// as sparse labels; deterministic for a given seed.
cv::Mat SampleSparse(const cv::Mat& dense, double fraction, uint64_t seed);

// Opens a training sequence through the camera pair the network learns from:
// the colour pair 02/03 of a KITTI raw drive (paper 5.1), the grey pair
// otherwise. Training and the export's training camera (baseline, f_x) both
// open sequences here, so the model's metadata names the pair it saw.
CameraPair TrainingCameraPair(const std::string& root);
std::unique_ptr<SequenceReader> OpenTrainingSequence(const std::string& root);

// Labels written by `dvso labels` name the stereo pair they were made on (labels_summary.json beside the
// left labels, or one folder up for right/); labels of another pair than `training_pair` supervise the
// wrong pixels (KITTI's colour cameras sit ~6 cm from the grey ones, and extract drives drop other frames):
// throws dvso::Error naming the summary. Folders without a summary (hand-made labels) are not checked.
void RequireLabelsOfTrainingPair(const std::string& label_dir, CameraPair training_pair);

// The sequence folders a dataset trains on, in order of first use, as StereoDataset
// opens them: `sequences`, or the drives of `split_file` (read here; errors name it)
// under `split_root` (default: the split file's folder).
std::vector<std::string> TrainingSequenceRoots(const DataOptions& options);

// Stereo pairs from the core sequence readers (KITTI odometry layout, the
// simulator, KITTI raw drives through their colour pair 02/03, rectified on read
// for _extract drives), all frames of `sequences` or the lines of `split_file`.
class StereoDataset {
 public:
  StereoDataset(const DataOptions& options, int network_width, int network_height);
  int size() const { return static_cast<int>(items_.size()); }
  // Loads sample i (no augmentation). Throws dvso::Error naming the file.
  StereoSample Load(int index) const;
  // Human-readable summary (sequences, frames, label source per sequence).
  std::string Describe() const;

 private:
  struct Sequence {
    std::string root;
    std::unique_ptr<SequenceReader> reader;
    std::string left_labels, right_labels;            // label folders ("" = none)
    bool labels_are_dense_gt = false;                 // sample them sparsely (simulator fallback)
  };
  struct Item {
    int sequence;
    int frame;                  // reader index
    bool mirrored = false;      // split side 'r': the right view is the network's left (FlipAndSwap)
  };
  int AddSequence(const std::string& root);  // index of the (possibly already open) sequence
  void AddSplit(const std::string& split_file);
  void ReadImages(const Sequence& seq, int frame, cv::Mat* left, cv::Mat* right) const;
  cv::Mat ReadLabel(const Sequence& seq, const std::string& dir, int frame, int side) const;

  DataOptions options_;
  int width_, height_;
  std::vector<Sequence> sequences_;
  std::vector<Item> items_;
};

}  // namespace dvso::stacknet
