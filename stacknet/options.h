// Option structs of StackNet (paper section 3 and 5.1). Every field has a
// default and a comment; Check() throws dvso::Error on invalid values. They are
// filled from a YAML config by stacknet/config.h (strict keys).
#pragma once

#include <string>
#include <vector>

namespace dvso::stacknet {

// Architecture of SimpleNet / ResidualNet (paper section 3.1).
struct NetworkOptions {
  int encoder_depth = 50;             // ResNet depth of SimpleNet's encoder: 18, 34 or 50 (paper: 50)
  double width_multiplier = 1.0;      // scales every channel count (1 = paper); < 1 for CPU configs
  int input_height = 256;             // network input height in pixels (paper: 256); multiple of 32
  int input_width = 512;              // network input width in pixels (paper: 512); multiple of 32
  double max_disparity = 0.3;         // sigmoid output scale, as a fraction of the width (monodepth)
  double residual_leaky_slope = 0.1;  // negative slope of ResidualNet's leaky ReLUs
  int residual_blocks = 12;           // residual blocks in ResidualNet's encoder (paper: 12); multiple of 4
  // Normalisation after every encoder convolution: "group" (GroupNorm, batch-size free, same in training and
  // inference) or "none" (monodepth's plain encoder). From scratch and without pretrained weights, the plain
  // encoder's signal shrinks through ~20 convolutions and it learned a constant map in 300 steps on 60 frames;
  // with GroupNorm the same run fits the frames (docs/stacknet.md).
  std::string normalization = "group";
  // SimpleNet's output at initialisation, as a fraction of the width (0 = LibTorch's default bias 0, i.e.
  // max_disparity / 2). 0.02 ~ a street scene's median disparity (KITTI: ~25 px of 1242 at ~15 m).
  double initial_disparity = 0.02;
  // ResidualNet's 13 input channels standardised to a common scale (images (I - 0.45) / 0.225, disparity / 0.05,
  // reconstruction error / 0.1) instead of raw: raw, the disparity and error channels are ~10x smaller than the
  // images, so with Adam (equal step sizes per weight) their first-layer weights need ~10x more steps to matter.
  // false = the layout of every model exported before session 18.
  bool standardize_residual_inputs = false;
  void Check() const;
};

// Weights of the loss terms of eq. (1); alpha_smooth is divided by 2^s at scale s.
struct LossOptions {
  double alpha_u = 1.0;          // self-supervised photometric term L_U (eq. 2)
  double alpha_s = 10.0;         // supervised berHu term L_S (eq. 3)
  double alpha_lr = 1.0;         // left-right consistency L_lr (eq. 4)
  double alpha_smooth = 0.1;     // second-order edge-aware smoothness L_smooth (eq. 5), / 2^s
  double alpha_occ = 0.01;       // occlusion regulariser L_occ (eq. 6)
  double ssim_alpha = 0.84;      // SSIM vs L1 balance inside L_U (eq. 2)
  double berhu_fraction = 0.2;   // berHu threshold = fraction * max |residual| over labelled pixels
  bool relative_supervision = false;  // L_S on r * mean(label) / label (far labels weigh as near ones); paper: false
  int num_scales = 4;            // output scales summed in eq. (1)
  void Check() const;
};

// Where training pairs come from.
struct DataOptions {
  std::vector<std::string> sequences;  // stereo sequence folders (KITTI odometry layout / dvso simulate / KITTI raw drive)
  std::string split_file;              // optional monodepth split "<drive> <frame> <side>" per line (core/depth_split.h), overrides all frames
  std::string split_root = "";         // folder the split's drive paths are relative to; "" = the split file's folder
  std::string label_dir_left = "labels";    // per-sequence folder of sparse left labels (uint16 PNG); "" = none
  std::string label_dir_right = "";         // per-sequence folder of sparse right labels; "" = none
  std::string gt_disparity_left = "disp_0"; // fallback when a sequence has no label folder: sample its GT
  std::string gt_disparity_right = "disp_1";// right GT used by the same fallback ("" = none)
  double gt_sample_fraction = 0.02;    // share of GT pixels kept by the fallback (sparse, like Stereo DSO)
  int frame_step = 1;                  // use every n-th frame of each sequence
  bool use_color = true;               // use colour images when present (grey replicated to 3 channels otherwise)
  void Check() const;
};

// Random photometric + flip augmentation (monodepth, paper section 5.1).
struct AugmentOptions {
  bool enabled = true;               // master switch
  double probability = 0.5;          // chance that a sample gets the photometric augmentation
  double gamma_min = 0.8;            // random gamma range
  double gamma_max = 1.2;
  double brightness_min = 0.5;       // random brightness factor range
  double brightness_max = 2.0;
  double color_min = 0.8;            // per-channel colour factor range
  double color_max = 1.2;
  double flip_probability = 0.5;     // horizontal flip with left/right swap
  double grey_probability = 0.0;     // chance that both views become grey (BT.601 luma in all 3 channels), as
                                     // DVSO feeds a grey camera (KITTI image_0); 0 = off, not in the paper
  void Check() const;
};

// One training stage (paper 5.1: K_o semi-sup, K_r self-sup, K_o supervised-only).
struct StageOptions {
  std::string name = "stage";        // shown in logs and checkpoints
  std::string model = "simple";      // "simple" trains SimpleNet; "stack" trains ResidualNet with SimpleNet frozen
  int epochs = 1;                    // epochs of this stage
  double learning_rate = 1e-4;       // Adam learning rate at the stage start
  int lr_halving_start = -1;         // first epoch (0-based, within the stage) at which the LR is halved; -1 = never
  int lr_halving_every = 0;          // halve again every n epochs after that; 0 = only once
  bool use_unsupervised = true;      // L_U on
  bool use_supervised = true;        // L_S on
  bool use_lr = true;                // L_lr on
  bool use_smooth = true;            // L_smooth on
  bool use_occ = true;               // L_occ on
  std::string data = "";             // optional: a named dataset from `datasets:` (e.g. K_o / K_r); "" = default data
  int max_steps_per_epoch = 0;       // 0 = full epoch; > 0 caps the batches per epoch (tests, quick runs)
  void Check() const;
  // Learning rate in epoch `epoch` (0-based, within the stage).
  double LearningRateAt(int epoch) const;
};

// The whole training run.
struct TrainOptions {
  std::string output_dir = "runs/stacknet";  // checkpoints and logs go here
  int batch_size = 8;                // paper: 8
  int num_workers = 2;               // loader threads
  int seed = 42;                     // data order and augmentation seed (resume is exact)
  double adam_beta1 = 0.9;
  double adam_beta2 = 0.999;
  double adam_epsilon = 1e-8;
  std::string device = "auto";       // auto | cpu | cuda
  int num_threads = 0;               // CPU intra-op threads; 0 = hardware cores
  bool progress = true;              // progress bar on stderr
  // A model file from `dvso export` whose weights replace the seeded initialisation
  // (fine-tuning; "" = train from scratch). Ignored on resume: the checkpoint has the weights.
  std::string init_from;
  void Check() const;
};

struct StackNetConfig {
  NetworkOptions network;
  LossOptions loss;
  DataOptions data;
  AugmentOptions augment;
  TrainOptions train;
  std::vector<StageOptions> stages;
  // Extra named datasets that stages refer to by `data:` (paper: K_o / K_r).
  std::vector<std::pair<std::string, DataOptions>> datasets;
  void Check() const;
  const DataOptions& DataFor(const StageOptions& stage) const;
};

}  // namespace dvso::stacknet
