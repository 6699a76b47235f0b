// Monocular initialisation (DSO's CoarseInitializer, simplified): the first
// frame's selected points get inverse depths that are optimised jointly with
// the pose and affine brightness of every following frame, coarse to fine,
// by Levenberg-Marquardt with the inverse depths eliminated by the Schur
// complement (each depth is a 1x1 block). While there is little parallax the
// depths are unobservable; a smoothness prior (pull towards the mean of the
// neighbours' inverse depths) keeps them well-behaved. The scale is arbitrary:
// the mean inverse depth is normalised to 1 after every step (the photometric
// energy is invariant to it). Initialisation succeeds once enough frames were
// seen and the translation-induced parallax exceeds a threshold.
// Every frame is optimised from two starts, the lower energy wins: constant
// velocity, and the same with the rotation first aligned alone (points at
// infinity). At a turning start with little parallax the first alone can fall
// into the basin where a sideways translation over flat depths mimics the yaw.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "vo/frame/image_pyramid.h"
#include "vo/frontend/coarse_tracker.h"
#include "vo/frontend/pixel_selector.h"

namespace dvso::vo {

struct MonoInitializerOptions {
  int min_frames = 5;               // frames after the first before success is possible (DSO: 5 after "snapped")
  int max_frames = 60;              // give up and restart with a new first frame after this many
  double min_parallax_px = 6.0;     // median translation-only flow (level-0 px) needed for success
  double regularization = 50.0;     // weight of the neighbour smoothness prior on inverse depths
  int iterations_per_level = 8;     // LM iterations per pyramid level and frame
  double translation_prior = 0.0;   // per point: weight of |t|^2 (DSO's alpha term, prefers rotation at low parallax; 0 = off)
  void Check() const;
};

struct MonoInitialization {
  std::vector<ReferencePoint> points;          // first-frame points with inverse depths (mean ~1)
  Eigen::Isometry3d T_last_first = Eigen::Isometry3d::Identity();  // last frame <- first frame
  double affine_a = 0, affine_b = 0;          // I_last ~ exp(a) I_first + b
  double rmse = 0;
};

class MonoInitializer {
 public:
  MonoInitializer(const MonoInitializerOptions& options, const PixelSelectorOptions& selector,
                  const CoarseTrackerOptions& tracker);

  // Starts over with `first` as the reference frame.
  void SetFirstFrame(ImagePyramidPtr first);
  bool has_first_frame() const { return first_ != nullptr; }
  const ImagePyramidPtr& first_frame() const { return first_; }
  int frames_seen() const { return frames_; }

  // Adds a frame; returns true once initialised (then result() is valid).
  // Returns false while more frames are needed; when max_frames is exceeded or
  // the optimisation diverges, failed() becomes true and the caller restarts.
  bool AddFrame(const ImagePyramid& frame);
  bool failed() const { return failed_; }
  const MonoInitialization& result() const { return result_; }
  // Current estimate of the last added frame relative to the first one.
  const Eigen::Isometry3d& T_last_first() const { return T_; }

 private:
  struct InitPoint {
    float u, v;       // level 0
    double idepth;
    bool good = true;
  };
  using Vector8d = Eigen::Matrix<double, 8, 1>;
  using Matrix8d = Eigen::Matrix<double, 8, 8>;

  // Energy (and linear system when want_system) at one level.
  double Evaluate(const ImagePyramid& frame, int level, const Eigen::Isometry3d& T, double a, double b,
                  const std::vector<double>& idepths, bool want_system, Matrix8d* Hff, Vector8d* bf,
                  std::vector<Vector8d>* Hfp, std::vector<double>* Hpp, std::vector<double>* bp, int* num) const;
  void ComputeNeighbourMeans(const std::vector<double>& idepths, std::vector<double>* means) const;
  // One start of the joint pose / affine / inverse-depth optimisation and its result.
  struct Hypothesis {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  // frame <- first
    double a = 0, b = 0;
    std::vector<double> idepths;
    double energy = 0;  // final energy at level 0 (photometric + priors)
    int num = 1;        // residuals behind it
  };
  // Coarse-to-fine Levenberg-Marquardt from `start` (depths eliminated by Schur).
  Hypothesis RefineJointly(const ImagePyramid& frame, Hypothesis start) const;
  // Rotation + affine only (points at infinity), coarse to fine, from R_init.
  Eigen::Matrix3d AlignRotation(const ImagePyramid& frame, const Eigen::Matrix3d& R_init, double* a, double* b) const;
  double MedianTranslationFlow(const Eigen::Isometry3d& T) const;

  MonoInitializerOptions options_;
  PixelSelectorOptions selector_;
  CoarseTrackerOptions tracker_;
  ImagePyramidPtr first_;
  std::vector<InitPoint> points_;
  std::vector<std::vector<int>> neighbours_;
  Eigen::Isometry3d T_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();
  double a_ = 0, b_ = 0;
  int frames_ = 0;
  bool failed_ = false;
  MonoInitialization result_;
};

}  // namespace dvso::vo
