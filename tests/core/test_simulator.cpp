// Ground-truth consistency of the synthetic street (core/simulator.h): stereo
// and temporal photo-consistency through the GT disparity / depth / poses,
// depth * disparity = fx * b, determinism, and the written KITTI layout.
#include <gtest/gtest.h>


#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "core/simulator.h"
#include "core/simulator_path.h"
#include "core/trajectory.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {

namespace fs = std::filesystem;

SimulatorOptions SmallOptions(int width = 310, int height = 94) {
  SimulatorOptions o;
  o.trajectory_path = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/00.txt";
  o.first_frame = 120;
  o.num_frames = 3;
  o.camera = StereoCamera{}.Resized(width, height);
  o.texture_size = 256;
  o.vignetting = false;
  o.exposure_drift = false;
  o.noise = true;
  o.noise_sigma = 1.0;
  return o;
}

// Bilinear lookups; indices are clamped to the image (rows/columns at the border).
float Bilinear(const cv::Mat& image, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double tx = x - x0, ty = y - y0;
  auto at = [&](int xx, int yy) {
    return static_cast<double>(image.at<uint8_t>(std::min(yy, image.rows - 1), std::min(xx, image.cols - 1)));
  };
  return static_cast<float>((1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
                            ty * ((1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1)));
}
float BilinearF(const cv::Mat& map, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double tx = x - x0, ty = y - y0;
  auto at = [&](int xx, int yy) {
    return static_cast<double>(map.at<float>(std::min(yy, map.rows - 1), std::min(xx, map.cols - 1)));
  };
  return static_cast<float>((1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
                            ty * ((1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1)));
}

struct ErrorStats {
  int count = 0;
  double mean = 0, median = 0, p90 = 0;
};
ErrorStats Summarise(std::vector<float> errors) {
  ErrorStats s;
  s.count = static_cast<int>(errors.size());
  if (errors.empty()) return s;
  double sum = 0;
  for (float e : errors) sum += e;
  s.mean = sum / errors.size();
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  s.median = errors[errors.size() / 2];
  std::nth_element(errors.begin(), errors.begin() + errors.size() * 9 / 10, errors.end());
  s.p90 = errors[errors.size() * 9 / 10];
  return s;
}

// |left(x) - right(x - d(x) - shift)| over non-occluded pixels (left-right
// check between disp_0 and disp_1), 2-pixel border excluded.
ErrorStats StereoWarpError(const SimulatedFrame& f, double shift) {
  std::vector<float> errors;
  const cv::Mat& dl = f.disparity_left;
  const cv::Mat& dr = f.disparity_right;
  for (int y = 2; y < dl.rows - 2; ++y)
    for (int x = 2; x < dl.cols - 2; ++x) {
      const float d = dl.at<float>(y, x);
      if (d <= 0) continue;
      const double xr = x - d;
      if (xr < 2 || xr > dl.cols - 3) continue;
      // Non-occluded: the right view sees the same surface at xr.
      const float d_right = dr.at<float>(y, static_cast<int>(std::lround(xr)));
      if (std::abs(d_right - d) > 0.05f * d + 0.1f) continue;
      errors.push_back(std::abs(f.left.grey.at<uint8_t>(y, x) - Bilinear(f.right.grey, xr - shift, y)));
    }
  return Summarise(errors);
}

// |I_a(p) - I_b(q + offset)| over the pixels p of frame a that the GT relative
// pose maps to q in frame b without occlusion (depths agree within 2 %).
ErrorStats TemporalWarpError(const SimulatedFrame& a, const SimulatedFrame& b, const PinholeCamera& cam,
                             double offset_x, double offset_y) {
  const Eigen::Isometry3d T_b_a = b.T_first_camera.inverse() * a.T_first_camera;
  std::vector<float> errors;
  for (int y = 2; y < cam.height - 2; ++y)
    for (int x = 2; x < cam.width - 2; ++x) {
      const float z = a.left.depth.at<float>(y, x);
      if (z <= 0) continue;
      const Eigen::Vector3d p = T_b_a * (z * cam.Unproject(x, y));
      if (p.z() < 0.5) continue;
      const Eigen::Vector2d q = cam.Project(p);
      if (!cam.InImage(q.x(), q.y(), 2)) continue;
      if (std::abs(BilinearF(b.left.depth, q.x(), q.y()) - p.z()) > 0.02 * p.z()) continue;  // occluded in b
      const float warped = Bilinear(b.left.grey, q.x() + offset_x, q.y() + offset_y);
      errors.push_back(std::abs(a.left.grey.at<uint8_t>(y, x) - warped));
    }
  return Summarise(errors);
}

class SimulatorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { simulator_ = std::make_unique<StreetSimulator>(SmallOptions()); }
  static void TearDownTestSuite() { simulator_.reset(); }
  static std::unique_ptr<StreetSimulator> simulator_;
};
std::unique_ptr<StreetSimulator> SimulatorTest::simulator_;

TEST_F(SimulatorTest, RightImageWarpedByLeftDisparityReproducesLeft) {
  const SimulatedFrame f = simulator_->Render(0);
  const ErrorStats good = StereoWarpError(f, 0.0);
  const int pixels = f.left.grey.rows * f.left.grey.cols;
  EXPECT_GT(good.count, pixels / 2) << "too few non-occluded pixels with GT";
  // Noise sigma 1 in both images: |difference| has mean ~1.13; texture
  // interpolation adds a little.
  EXPECT_LT(good.median, 2.5);
  EXPECT_LT(good.mean, 3.0);
  // Sensitivity: a wrong disparity (2 px off) must be clearly worse.
  const ErrorStats wrong = StereoWarpError(f, 2.0);
  std::printf("stereo warp |error|: mean %.2f median %.2f p90 %.2f over %d px (2 px off: mean %.2f)\n", good.mean,
              good.median, good.p90, good.count, wrong.mean);
  EXPECT_GT(wrong.mean, 2.0 * good.mean);
}

TEST_F(SimulatorTest, DisparityIsFxBOverDepthAndRightDisparityIsConsistent) {
  const SimulatedFrame f = simulator_->Render(1);
  const double fxb = simulator_->camera().FxB();
  int valid = 0, consistent = 0;
  for (int y = 0; y < f.left.depth.rows; ++y)
    for (int x = 0; x < f.left.depth.cols; ++x) {
      const float z = f.left.depth.at<float>(y, x), d = f.disparity_left.at<float>(y, x);
      ASSERT_EQ(z > 0, d > 0);
      if (z <= 0) continue;
      ++valid;
      EXPECT_NEAR(z * d, fxb, 1e-4 * fxb);
      // The right view's depth at the corresponding pixel is the same (same
      // orientation, baseline along x) unless occluded.
      const double xr = x - d;
      if (xr >= 0 && xr <= f.left.depth.cols - 2) {
        const float zr = BilinearF(f.right.depth, xr, y);
        if (std::abs(zr - z) < 0.01f * z) ++consistent;
      }
    }
  EXPECT_GT(valid, f.left.depth.total() / 2);
  EXPECT_GT(consistent, valid * 8 / 10);
}

TEST_F(SimulatorTest, ReprojectionWithGtPoseIntoNextFrameIsPhotoConsistent) {
  const SimulatedFrame a = simulator_->Render(0);
  const SimulatedFrame b = simulator_->Render(1);
  const PinholeCamera& cam = simulator_->camera().left;
  const Eigen::Isometry3d T_b_a = b.T_first_camera.inverse() * a.T_first_camera;
  ASSERT_GT(T_b_a.translation().norm(), 0.3) << "the camera should move between frames";
  const ErrorStats good = TemporalWarpError(a, b, cam, 0.0, 0.0), bad = TemporalWarpError(a, b, cam, 3.0, 0.0);
  std::printf("temporal warp |error|: mean %.2f median %.2f p90 %.2f over %d px (3 px off: mean %.2f)\n", good.mean,
              good.median, good.p90, good.count, bad.mean);
  EXPECT_GT(good.count, static_cast<int>(cam.width * cam.height / 3));
  EXPECT_LT(good.median, 2.5);
  EXPECT_LT(good.mean, 3.5);
  EXPECT_GT(bad.mean, 2.0 * good.mean);
}

TEST_F(SimulatorTest, RoadIsCameraHeightBelowTheCamera) {
  const SimulatedFrame f = simulator_->Render(2);
  const PinholeCamera& cam = simulator_->camera().left;
  std::vector<float> heights;
  for (int y = cam.height - 6; y < cam.height; ++y)
    for (int x = cam.width / 2 - 10; x <= cam.width / 2 + 10; ++x) {
      const float z = f.left.depth.at<float>(y, x);
      ASSERT_GT(z, 0);
      heights.push_back(static_cast<float>(z * (y - cam.cy) / cam.fy));
    }
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  // Not exactly 1.65: the KITTI car pitches and the road height is smoothed.
  EXPECT_NEAR(heights[heights.size() / 2], 1.65, 0.15);
}

TEST_F(SimulatorTest, TextureEverywhereExceptSky) {
  SimulatorOptions o = SmallOptions(620, 188);
  o.noise = false;
  o.num_frames = 1;
  const StreetSimulator simulator(o);
  const SimulatedFrame f = simulator.Render(0);
  // Fraction of non-sky pixels with a visible intensity gradient nearby
  // (direct odometry needs gradients everywhere on the road and walls).
  int structure = 0, textured = 0, sky = 0;
  for (int y = 2; y < f.left.grey.rows - 2; ++y)
    for (int x = 2; x < f.left.grey.cols - 2; ++x) {
      if (f.left.depth.at<float>(y, x) <= 0) {
        ++sky;
        continue;
      }
      ++structure;
      int lo = 255, hi = 0;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int v = f.left.grey.at<uint8_t>(y + dy, x + dx);
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      if (hi - lo >= 3) ++textured;
    }
  EXPECT_GT(structure, 4 * sky) << "a street should be mostly structure, not sky";
  std::printf("textured: %.3f of %d structure pixels, sky %d\n", static_cast<double>(textured) / structure, structure,
              sky);
  EXPECT_GT(textured, structure * 85 / 100);
}

TEST(Simulator, DeterministicPerSeed) {
  SimulatorOptions o = SmallOptions(160, 48);
  o.num_frames = 1;
  o.exposure_drift = true;
  const SimulatedFrame a = StreetSimulator(o).Render(0);
  const SimulatedFrame b = StreetSimulator(o).Render(0);
  EXPECT_EQ(cv::norm(a.left.grey, b.left.grey, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a.right.grey, b.right.grey, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a.left.depth, b.left.depth, cv::NORM_INF), 0);
  o.seed = 2;
  const SimulatedFrame c = StreetSimulator(o).Render(0);
  EXPECT_GT(cv::norm(a.left.grey, c.left.grey, cv::NORM_L1), 0);
  // Thread count must not change the result.
  o.seed = 1;
  o.num_threads = 1;
  const SimulatedFrame d = StreetSimulator(o).Render(0);
  EXPECT_EQ(cv::norm(a.left.grey, d.left.grey, cv::NORM_INF), 0);
}

// --right-gain / --right-bias: the right camera's own response; the left view and the geometry stay.
TEST(Simulator, RightCameraGainAndBiasChangeOnlyTheRightImage) {
  SimulatorOptions o = SmallOptions(160, 48);
  o.num_frames = 1;
  o.noise = false;  // compare the responses without the noise draw
  const SimulatedFrame same = StreetSimulator(o).Render(0);
  o.right_gain = 1.2;
  o.right_bias = 7;
  const SimulatedFrame other = StreetSimulator(o).Render(0);
  EXPECT_EQ(cv::norm(same.left.grey, other.left.grey, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(same.right.depth, other.right.depth, cv::NORM_INF), 0);
  int compared = 0, off = 0;
  for (int y = 0; y < same.right.grey.rows; ++y) {
    for (int x = 0; x < same.right.grey.cols; ++x) {
      const double expected = 1.2 * same.right.grey.at<uint8_t>(y, x) + 7.0;
      if (expected > 250) continue;  // saturated
      ++compared;
      // Both images are rounded to 8 bits: the bias enters before the rounding, the gain scales the other's rounding.
      off += std::abs(other.right.grey.at<uint8_t>(y, x) - expected) > 1.2 * 0.5 + 0.5 + 1e-9;
    }
  }
  EXPECT_GT(compared, same.right.grey.total() / 2);
  EXPECT_EQ(off, 0);
}

TEST(Simulator, RightCameraVignettingChangesOnlyTheRightImageByItsFallOff) {
  SimulatorOptions o = SmallOptions(160, 48);
  o.num_frames = 1;
  o.noise = false;
  o.vignetting = true;  // 0.3 in both cameras
  const SimulatedFrame same = StreetSimulator(o).Render(0);
  o.right_vignetting_strength = 0.0;  // the right camera without fall-off, the left one keeps 0.3
  const SimulatedFrame flat = StreetSimulator(o).Render(0);
  EXPECT_EQ(cv::norm(same.left.grey, flat.left.grey, cv::NORM_INF), 0);
  // I = clamp(k * V(x) * L + b): without the fall-off the right image is I' = (I - b) / V(x) + b, so the
  // centre stays and the corners brighten by up to 1 / 0.7.
  const sim::Photometric p = StreetSimulator(o).Exposure(0, 1);
  EXPECT_EQ(p.vignetting_strength, 0.0);
  EXPECT_EQ(StreetSimulator(o).Exposure(0, 0).vignetting_strength, o.vignetting_strength);
  const PinholeCamera& c = o.camera.left;
  const double half_diagonal_sq = 0.25 * (c.width * c.width + c.height * c.height);
  int compared = 0, off = 0, brighter_corners = 0;
  for (int y = 0; y < same.right.grey.rows; ++y) {
    for (int x = 0; x < same.right.grey.cols; ++x) {
      const double r2 = (x - c.cx) * (x - c.cx) + (y - c.cy) * (y - c.cy);
      const double v = 1.0 - o.vignetting_strength * r2 / half_diagonal_sq;
      const double expected = (same.right.grey.at<uint8_t>(y, x) - p.bias) / v + p.bias;
      if (expected > 250 || same.right.grey.at<uint8_t>(y, x) < 5) continue;  // clipped
      ++compared;
      const int got = flat.right.grey.at<uint8_t>(y, x);
      off += std::abs(got - expected) > 0.5 / v + 0.5 + 1e-9;  // both rounded to 8 bits
      if (r2 > 0.8 * half_diagonal_sq) brighter_corners += got > same.right.grey.at<uint8_t>(y, x);
    }
  }
  EXPECT_GT(compared, static_cast<int>(same.right.grey.total() / 2));
  EXPECT_EQ(off, 0);
  EXPECT_GT(brighter_corners, 20);
}

TEST(Simulator, RejectsBadOptions) {
  auto expect_error = [](const std::function<void(SimulatorOptions&)>& change) {
    SimulatorOptions o = SmallOptions(160, 48);
    change(o);
    EXPECT_THROW(StreetSimulator{o}, Error);
  };
  expect_error([](SimulatorOptions& o) { o.stride = 0; });
  expect_error([](SimulatorOptions& o) { o.num_frames = 0; });
  expect_error([](SimulatorOptions& o) { o.first_frame = -1; });
  expect_error([](SimulatorOptions& o) { o.first_frame = 100000; });
  expect_error([](SimulatorOptions& o) { o.num_frames = 5000; });
  expect_error([](SimulatorOptions& o) { o.trajectory_path = "/nonexistent/poses.txt"; });
  expect_error([](SimulatorOptions& o) { o.texture_size = 300; });
  expect_error([](SimulatorOptions& o) { o.noise_sigma = -1; });
  expect_error([](SimulatorOptions& o) { o.right_vignetting_strength = 1.0; });
  expect_error([](SimulatorOptions& o) { o.camera.baseline = 0; });
  expect_error([](SimulatorOptions& o) { o.camera.left.width = 8; });
  expect_error([](SimulatorOptions& o) { o.scene.building_density = 1.5; });
  expect_error([](SimulatorOptions& o) { o.exposure_level = 0; });
  expect_error([](SimulatorOptions& o) { o.height_jitter = -0.01; });
  expect_error([](SimulatorOptions& o) { o.car_detail = 1.5; });
  expect_error([](SimulatorOptions& o) { o.right_gain = 0.3; });
  expect_error([](SimulatorOptions& o) { o.right_bias = 50; });
  expect_error([](SimulatorOptions& o) {
    o.trajectory_path.clear();
    o.num_frames = -1;
  });
}

TEST(Simulator, GeneratedPathIsSmoothAndStartsAtIdentity) {
  const auto poses = sim::GenerateDrivingPath(200, 10.0, 0.1, 3);
  ASSERT_EQ(poses.size(), 200u);
  EXPECT_TRUE(poses[0].isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  for (size_t i = 1; i < poses.size(); ++i) {
    const double step = (poses[i].translation() - poses[i - 1].translation()).norm();
    EXPECT_GT(step, 0.3);
    EXPECT_LT(step, 1.5);
    const Eigen::AngleAxisd turn(poses[i - 1].linear().transpose() * poses[i].linear());
    EXPECT_LT(turn.angle(), 0.12) << "frame " << i;
  }
}

TEST(Simulator, WritesKittiLayoutWithGroundTruth) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("sim_test"));
  fs::remove_all(dir);
  SimulatorOptions o = SmallOptions(160, 48);
  o.num_frames = 3;
  o.stride = 2;
  o.exposure_drift = true;
  o.vignetting = true;
  o.right_vignetting_strength = 0.1;  // the right lens has its own fall-off: written as vignette_right.png
  const SimulationSummary summary = WriteSimulatedSequence(o, dir.string(), false);
  EXPECT_EQ(summary.frames, 3);
  for (const char* sub : {"image_0", "image_1", "depth_0", "disp_0", "disp_1"})
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(fs::exists(dir / sub / FrameFileName(i, ".png"))) << sub << " " << i;
  EXPECT_FALSE(fs::exists(dir / "image_2"));
  // calib.txt carries fx and the baseline.
  const StereoCamera cam = ReadKittiCalibration((dir / "calib.txt").string(), 160, 48);
  EXPECT_NEAR(cam.left.fx, o.camera.left.fx, 1e-6);
  EXPECT_NEAR(cam.baseline, 0.537, 1e-9);
  // poses.txt: GT relative to the first written frame; times in 0.1 s * stride.
  const Trajectory poses = ReadTrajectory((dir / "poses.txt").string());
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_TRUE(poses.poses[0].T_world_camera.isApprox(Eigen::Isometry3d::Identity(), 1e-9));
  // They are KITTI's poses with the altitude drift of its revisits corrected (sim::AltitudeCorrections).
  const Trajectory kitti = ReadTrajectory(o.trajectory_path);
  std::vector<Eigen::Isometry3d> corrected;
  for (const auto& p : kitti.poses) corrected.push_back(p.T_world_camera);
  sim::ApplyAltitudeCorrections(sim::AltitudeCorrections(corrected, {}), &corrected);
  const Eigen::Isometry3d expected = corrected[120].inverse() * corrected[124];
  EXPECT_TRUE(poses.poses[2].T_world_camera.isApprox(expected, 1e-6));
  // --world-version 1: KITTI's poses as they are.
  o.world_version = 1;
  const StreetSimulator raw(o);
  const Eigen::Isometry3d raw_expected = kitti.poses[120].T_world_camera.inverse() * kitti.poses[124].T_world_camera;
  EXPECT_TRUE((raw.WorldFromCamera(0).inverse() * raw.WorldFromCamera(2)).isApprox(raw_expected, 1e-6));
  EXPECT_FALSE(raw_expected.isApprox(expected, 1e-6));  // the correction is not a no-op here
  const std::vector<double> times = ReadTimes((dir / "times.txt").string());
  ASSERT_EQ(times.size(), 3u);
  EXPECT_NEAR(times[2] - times[1], 0.2, 1e-9);
  // Maps on disk: depth * disparity = fx * b up to the 1/256 quantisation.
  const cv::Mat depth = ReadKittiMapPng((dir / "depth_0" / "000001.png").string());
  const cv::Mat disparity = ReadKittiMapPng((dir / "disp_0" / "000001.png").string());
  int valid = 0;
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const float z = depth.at<float>(y, x), d = disparity.at<float>(y, x);
      if (z <= 0 || d <= 0) continue;
      ++valid;
      EXPECT_NEAR(z * d, cam.FxB(), (z + d) * 0.5 / 256 + 1e-3);
    }
  EXPECT_GT(valid, depth.rows * depth.cols / 2);
  // The sequence reader opens what we wrote.
  const auto reader = OpenSequence(dir.string());
  EXPECT_EQ(reader->size(), 3);
  EXPECT_EQ(reader->Read(2).left.cols, 160);
  EXPECT_TRUE(fs::exists(dir / "exposures.txt"));
  // Each lens's V(x) = 1 - strength r^2 / half_diagonal^2, at the top-left pixel (r measured from the
  // principal point) by hand.
  const PinholeCamera& c = o.camera.left;
  const double corner_r2_ratio = (c.cx * c.cx + c.cy * c.cy) / (0.25 * (160.0 * 160.0 + 48.0 * 48.0));
  const cv::Mat left_vignette = cv::imread((dir / "vignette.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat right_vignette = cv::imread((dir / "vignette_right.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(left_vignette.empty());
  ASSERT_FALSE(right_vignette.empty());
  EXPECT_NEAR(left_vignette.at<uint16_t>(0, 0), 65535.0 * (1 - o.vignetting_strength * corner_r2_ratio), 1.0);
  EXPECT_NEAR(right_vignette.at<uint16_t>(0, 0), 65535.0 * (1 - 0.1 * corner_r2_ratio), 1.0);

  // A rerun into the same folder without vignetting leaves no vignette map of the first run; with a
  // 9.5 m baseline at 480x144 the near road has disparities beyond the PNG's 255.996 px: invalid (0),
  // never clamped.
  const int frames = o.num_frames, stride = o.stride;
  o = SmallOptions(480, 144);
  o.num_frames = frames;
  o.stride = stride;
  o.vignetting = false;
  o.camera.baseline = 9.5;
  WriteSimulatedSequence(o, dir.string(), false);
  EXPECT_FALSE(fs::exists(dir / "vignette.png"));
  EXPECT_FALSE(fs::exists(dir / "vignette_right.png"));
  const double fx_b = o.camera.left.fx * o.camera.baseline;
  int beyond = 0, right = 0;
  for (const char* sub : {"disp_0", "disp_1"}) {
    const cv::Mat far_depth = ReadKittiMapPng((dir / "depth_0" / "000001.png").string());
    const cv::Mat long_baseline = ReadKittiMapPng((dir / sub / "000001.png").string());
    for (int y = 0; y < long_baseline.rows; ++y)
      for (int x = 0; x < long_baseline.cols; ++x) {
        const float d = long_baseline.at<float>(y, x);
        EXPECT_LT(d, kKittiMapMaxValue) << sub << " (" << x << ", " << y << ")";
        const float z = far_depth.at<float>(y, x);
        if (std::string(sub) == "disp_0" && z > 0 && fx_b / z > kKittiMapMaxValue) {
          ++beyond;
          EXPECT_EQ(d, 0.f) << "(" << x << ", " << y << ")";
        }
        if (std::string(sub) == "disp_0" && z > 0 && d > 0) {
          ++right;
          EXPECT_NEAR(z * d, fx_b, (z + d) * 0.5 / 256 + 1e-3);
        }
      }
  }
  EXPECT_GT(beyond, 0);
  EXPECT_GT(right, 0);
  fs::remove_all(dir);
}

// Mean colour (B, G, R) of the structure pixels and the mean sky brightness, pooled over every frame of `o`.
struct LookStats {
  cv::Scalar structure;
  double sky = 0;
};
LookStats Look(const SimulatorOptions& o) {
  const StreetSimulator simulator(o);
  cv::Scalar structure_sum(0, 0, 0, 0);
  double sky_sum = 0;
  int structure_pixels = 0, sky_pixels = 0;
  for (int i = 0; i < o.num_frames; ++i) {
    const SimulatedFrame f = simulator.Render(i);
    const cv::Mat structure_mask = f.left.depth > 0, sky_mask = f.left.depth <= 0;
    const int n_structure = cv::countNonZero(structure_mask), n_sky = cv::countNonZero(sky_mask);
    structure_sum += cv::mean(f.left.color, structure_mask) * n_structure;
    if (n_sky > 0) sky_sum += cv::mean(f.left.grey, sky_mask)[0] * n_sky;
    structure_pixels += n_structure;
    sky_pixels += n_sky;
  }
  LookStats s;
  s.structure = structure_sum * (1.0 / std::max(structure_pixels, 1));
  s.sky = sky_pixels > 0 ? sky_sum / sky_pixels : 0;
  return s;
}

TEST(Simulator, VariedAppearanceChangesTheLookPerSeed) {
  // The varied look is drawn from the seed and deterministic; the fixed look is the default.
  const sim::Appearance a1 = sim::RandomAppearance(1), a1b = sim::RandomAppearance(1), a2 = sim::RandomAppearance(2);
  EXPECT_TRUE(a1.varied);
  EXPECT_EQ(a1.sun_strength, a1b.sun_strength);
  EXPECT_NE(a1.sun_strength, a2.sun_strength);
  EXPECT_FALSE(sim::Appearance{}.varied);
  // Over 5 seeds, the spread of the mean brightness and of the colour balance of
  // the structure pixels is much larger with the varied look than with the fixed one.
  // Each seed's look is pooled over six views 100 poses apart: one view is often filled
  // by a single facade, whose texture (drawn from the seed's layout in both looks) would
  // decide the fixed look's spread; over 600 poses the facades average out while the
  // varied look's light, exposure and tints, which apply everywhere, remain.
  auto spread = [](bool varied) {
    double lo = 1e9, hi = -1e9, balance_lo = 1e9, balance_hi = -1e9;
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      SimulatorOptions o = SmallOptions(160, 48);
      o.num_frames = 6;
      o.stride = 100;
      o.color = true;
      o.noise = false;
      o.seed = seed;
      o.vary_appearance = varied;
      const LookStats s = Look(o);
      const double mean = (s.structure[0] + s.structure[1] + s.structure[2]) / 3;
      const double balance = (s.structure[2] - s.structure[0]) / std::max(mean, 1.0);  // red - blue
      lo = std::min(lo, mean);
      hi = std::max(hi, mean);
      balance_lo = std::min(balance_lo, balance);
      balance_hi = std::max(balance_hi, balance);
    }
    return std::make_pair(hi - lo, balance_hi - balance_lo);
  };
  const auto fixed = spread(false), varied = spread(true);
  std::printf("brightness spread over seeds: fixed %.1f varied %.1f; colour balance spread: fixed %.3f varied %.3f\n",
              fixed.first, varied.first, fixed.second, varied.second);
  EXPECT_GT(varied.first, 20.0);
  EXPECT_GT(varied.first, 2.0 * fixed.first);
  EXPECT_GT(varied.second, 1.5 * fixed.second);
}

TEST(Simulator, CarDetailChangesOnlyTheCarsPaint) {
  // --car-detail 1 against 0 on the same world: the geometry (depth) is identical, only pixels change, and those
  // that change carry more texture with the detailed paint (cars are what it paints). The texture is measured
  // inside the car bodies: changed pixels whose 3x3 depth neighbourhood varies by < 5 %; at a silhouette the
  // contrast against what lies behind the car, not the paint, sets the gradient. Pooled over four views 40
  // poses apart along streets with parking lanes: many cars at several distances and of several paints, not
  // the one or two a single view may hold (a dark car's paint gives smaller gradients in grey levels).
  SimulatorOptions o = SmallOptions(620, 188);
  o.first_frame = 300;
  o.num_frames = 4;
  o.stride = 40;
  o.noise = false;
  o.scene.car_density = 1.0;
  o.car_detail = 0;
  const StreetSimulator plain_world(o);
  o.car_detail = 1;
  const StreetSimulator detailed_world(o);
  o.car_detail = 0.5;
  const StreetSimulator half_world(o);
  auto abs_x_gradient = [](const cv::Mat& grey) {
    cv::Mat g;
    cv::Sobel(grey, g, CV_32F, 1, 0);
    return cv::Mat(cv::abs(g));
  };
  int num_changed = 0, half_changed = 0, num_pixels = 0;
  int num_body = 0;
  double gradient_plain = 0, gradient_detailed = 0;  // sums of |d/dx| over the changed pixels inside car bodies
  for (int i = 0; i < o.num_frames; ++i) {
    const SimulatedFrame plain = plain_world.Render(i), detailed = detailed_world.Render(i);
    EXPECT_EQ(cv::countNonZero(plain.left.depth != detailed.left.depth), 0) << "view " << i;
    cv::Mat changed = cv::abs(plain.left.grey - detailed.left.grey) > 0;
    // Away from the borders, where the horizontal neighbour exists.
    changed.col(0).setTo(0);
    changed.col(changed.cols - 1).setTo(0);
    const int n = cv::countNonZero(changed);
    num_changed += n;
    num_pixels += static_cast<int>(changed.total());
    cv::Mat depth_max, depth_min;
    cv::dilate(plain.left.depth, depth_max, cv::Mat());
    cv::erode(plain.left.depth, depth_min, cv::Mat());
    const cv::Mat body = changed & (depth_max < 1.05 * depth_min) & (depth_min > 0);
    const int n_body = cv::countNonZero(body);
    num_body += n_body;
    gradient_plain += cv::mean(abs_x_gradient(plain.left.grey), body)[0] * n_body;
    gradient_detailed += cv::mean(abs_x_gradient(detailed.left.grey), body)[0] * n_body;
    half_changed += cv::countNonZero(cv::abs(plain.left.grey - half_world.Render(i).left.grey) > 0);
  }
  std::printf("car detail changed %d of %d pixels\n", num_changed, num_pixels);
  ASSERT_GT(num_changed, num_pixels / 50) << "car_detail changed nothing (broken, or no car in view)";
  ASSERT_GT(num_body, num_changed / 2);
  const double g_plain = gradient_plain / num_body, g_detailed = gradient_detailed / num_body;
  std::printf("mean |d/dx| on %d changed pixels inside car bodies: plain %.2f detailed %.2f\n", num_body, g_plain,
              g_detailed);
  EXPECT_GT(g_detailed, 1.5 * g_plain);
  // A share of 0.5 paints some of the cars in view, not all and not none.
  std::printf("car detail 0.5 changed %d pixels\n", half_changed);
  EXPECT_GT(half_changed, num_changed / 10);
  EXPECT_LT(half_changed, num_changed * 9 / 10);
  // The fixed look has none, the varied one draws a share in [kVariedCarDetailMin, 1].
  EXPECT_EQ(sim::Appearance{}.car_detail, 0.f);
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const float share = sim::RandomAppearance(seed).car_detail;
    EXPECT_GE(share, sim::kVariedCarDetailMin);
    EXPECT_LE(share, 1.f);
  }
}

TEST(Simulator, VariedAppearanceKeepsTheGroundTruthExact) {
  SimulatorOptions o = SmallOptions();
  o.seed = 5;
  o.vary_appearance = true;
  o.num_frames = 2;
  const StreetSimulator simulator(o);
  EXPECT_TRUE(simulator.scene().appearance.varied);
  EXPECT_NEAR(simulator.options().camera_height, 1.65, 0.1 + 1e-12);
  EXPECT_GT(simulator.options().height_jitter, 0.0);
  const SimulatedFrame a = simulator.Render(0), b = simulator.Render(1);
  // Stereo: the right image warped by the GT disparity reproduces the left one; d * z = fx * b.
  const ErrorStats stereo = StereoWarpError(a, 0.0), wrong = StereoWarpError(a, 2.0);
  EXPECT_GT(stereo.count, a.left.grey.total() / 2);
  EXPECT_LT(stereo.median, 2.5);
  EXPECT_GT(wrong.mean, 2.0 * stereo.mean);
  const double fxb = simulator.camera().FxB();
  for (int y = 0; y < a.left.depth.rows; y += 3)
    for (int x = 0; x < a.left.depth.cols; x += 3) {
      const float z = a.left.depth.at<float>(y, x);
      if (z > 0) {
        ASSERT_NEAR(z * a.disparity_left.at<float>(y, x), fxb, 1e-4 * fxb);
      }
    }
  // Temporal: the GT poses (height bounce included) reproject frame 0 into frame 1.
  const PinholeCamera& cam = simulator.camera().left;
  const ErrorStats temporal = TemporalWarpError(a, b, cam, 0.0, 0.0), off = TemporalWarpError(a, b, cam, 0.0, 2.0);
  EXPECT_GT(temporal.count, static_cast<int>(cam.width * cam.height / 3));
  EXPECT_LT(temporal.median, 2.5);
  EXPECT_GT(off.mean, 1.5 * temporal.mean) << "a 2 px vertical error (a missing height bounce) must show";
}

TEST(Simulator, HeightJitterMovesTheCameraAlongDownWithinItsBound) {
  SimulatorOptions o = SmallOptions(64, 32);
  o.num_frames = 30;
  const StreetSimulator plain(o);
  o.height_jitter = 0.04;
  const StreetSimulator bouncing(o);
  const Eigen::Vector3d down = bouncing.scene().down;
  double max_offset = 0;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d d =
        bouncing.Render(i).T_world_camera.translation() - plain.Render(i).T_world_camera.translation();
    EXPECT_NEAR((d - d.dot(down) * down).norm(), 0.0, 1e-9) << "only the height changes";
    EXPECT_LE(std::abs(d.dot(down)), 0.04 + 1e-12);
    max_offset = std::max(max_offset, std::abs(d.dot(down)));
  }
  EXPECT_GT(max_offset, 0.01);
}

// Number of scene triangles that the straight segment p -> q passes through.
int TrianglesCrossed(const sim::Scene& scene, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  int crossed = 0;
  const Eigen::Vector3d mid = 0.5 * (p + q);
  const double half = 0.5 * (q - p).norm();
  for (const sim::Chunk& chunk : scene.chunks) {
    if ((chunk.center - mid).norm() > chunk.radius + half) continue;
    for (int i = chunk.begin; i < chunk.end; ++i) {
      const sim::Triangle& t = scene.triangles[i];
      const double dp = t.normal.dot(p) - t.offset, dq = t.normal.dot(q) - t.offset;
      if (dp * dq > 0 || dp == dq) continue;
      const Eigen::Vector3d x = p + dp / (dp - dq) * (q - p);
      // Barycentric coordinates of x in the triangle.
      const Eigen::Vector3d e0 = t.v[1] - t.v[0], e1 = t.v[2] - t.v[0], w = x - t.v[0];
      const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = w.dot(e0), d21 = w.dot(e1);
      const double den = d00 * d11 - d01 * d01;
      const double b1 = (d11 * d20 - d01 * d21) / den, b2 = (d00 * d21 - d01 * d20) / den;
      if (b1 >= 0 && b2 >= 0 && b1 + b2 <= 1) ++crossed;
    }
  }
  return crossed;
}

// The cameras never drive through an object. KITTI 10 climbs ~10 m on a
// curve around frame 927: a building placed beside a lower part of that
// street was once allowed to stand across the higher part (the path there
// counted as a bridge), and both cameras drove through its wall.
TEST(Simulator, CamerasNeverPassThroughTheWorld) {
  struct Case {
    std::string poses;
    int first, count;
    uint64_t seed;
  };
  const std::vector<Case> cases = {{"10.txt", 780, 280, 1001}, {"10.txt", 780, 280, 7}, {"00.txt", 0, 300, 3}};
  for (const Case& c : cases) {
    SimulatorOptions o;
    o.trajectory_path = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/" + c.poses;
    o.first_frame = c.first;
    o.num_frames = c.count;
    o.seed = c.seed;
    o.vary_appearance = true;
    o.texture_size = 64;
    const StreetSimulator sim(o);
    const Eigen::Vector3d right_offset(o.camera.baseline, 0, 0);
    for (int i = 0; i + 1 < sim.num_frames(); ++i) {
      const Eigen::Isometry3d a = sim.WorldFromCamera(i), b = sim.WorldFromCamera(i + 1);
      EXPECT_EQ(TrianglesCrossed(sim.scene(), a.translation(), b.translation()), 0)
          << c.poses << " seed " << c.seed << ": left camera between frames " << i << " and " << i + 1;
      EXPECT_EQ(TrianglesCrossed(sim.scene(), a * right_offset, b * right_offset), 0)
          << c.poses << " seed " << c.seed << ": right camera between frames " << i << " and " << i + 1;
    }
  }
}

TEST(Simulator, CommandLine) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("sim_cli"));
  fs::remove_all(dir);
  const std::string dvso = DVSO_BINARY;
  const std::string ok = dvso + " simulate --width 128 --height 40 --count 2 --seed 4 --texture-size 128 --quiet --out " +
                         dir.string() + " > /dev/null 2>&1";
  EXPECT_EQ(std::system(ok.c_str()), 0);
  EXPECT_TRUE(fs::exists(dir / "image_1" / "000001.png"));
  EXPECT_TRUE(fs::exists(dir / "poses.txt"));
  const std::string varied = dvso + " simulate --width 128 --height 40 --count 1 --seed 4 --texture-size 128 --quiet "
                                    "--appearance varied --out " + dir.string() + "_varied > /dev/null 2>&1";
  EXPECT_EQ(std::system(varied.c_str()), 0);
  EXPECT_TRUE(fs::exists(dir.string() + "_varied/image_0/000000.png"));
  fs::remove_all(dir.string() + "_varied");
  const std::string wrong_look = dvso + " simulate --count 1 --appearance pretty --out " + dir.string() + " > /dev/null 2>&1";
  EXPECT_NE(std::system(wrong_look.c_str()), 0);
  const std::string bad = dvso + " simulate --count 2 --stride 0 --out " + dir.string() + " > /dev/null 2>&1";
  EXPECT_NE(std::system(bad.c_str()), 0);
  // Options that would be silently replaced or unused are errors: the varied look draws the exposure
  // level from the seed; --raw-out / --raw-drive only act with a raw layout.
  const std::string small = dvso + " simulate --width 128 --height 40 --count 1 --texture-size 128 --quiet --out " +
                            dir.string() + "_unused";
  for (const char* unused : {" --appearance varied --exposure-level 0.7", " --raw-out /tmp/unused_raw", " --raw-drive 3"}) {
    const std::string command = small + unused + " > /dev/null 2>&1";
    EXPECT_NE(std::system(command.c_str()), 0) << unused;
  }
  const std::string fixed_level = small + " --exposure-level 0.7 > /dev/null 2>&1";
  EXPECT_EQ(std::system(fixed_level.c_str()), 0);
  fs::remove_all(dir.string() + "_unused");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dvso
