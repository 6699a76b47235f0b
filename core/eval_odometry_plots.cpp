// Figures of `dvso eval-odometry --plot-dir`: the top view (x-z plane, the
// ground plane of KITTI's camera frame) and the KITTI errors per segment length.
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/eval_odometry.h"
#include "core/fs_util.h"
#include "core/image_file.h"
#include "core/plot.h"

namespace dvso {

std::vector<std::string> WriteOdometryPlots(const std::string& dir, const Trajectory& gt, const Trajectory& aligned_est,
                        const OdometryMetrics& metrics) {
  EnsureDirectory(dir);
  const std::string est_label =
      metrics.align == AlignmentMode::kNone ? "estimate" : "estimate (" + AlignmentModeName(metrics.align) + "-aligned)";

  PlotSeries gt_series, est_series;
  gt_series.label = "ground truth";
  gt_series.color = cv::Scalar(0, 0, 0);
  est_series.label = est_label;
  est_series.color = cv::Scalar(30, 30, 220);
  for (const StampedPose& p : gt.poses) {
    gt_series.x.push_back(p.T_world_camera.translation().x());
    gt_series.y.push_back(p.T_world_camera.translation().z());
  }
  for (const StampedPose& p : aligned_est.poses) {
    est_series.x.push_back(p.T_world_camera.translation().x());
    est_series.y.push_back(p.T_world_camera.translation().z());
  }
  PlotSeries start;
  start.x = {gt_series.x.front()};
  start.y = {gt_series.y.front()};
  start.color = cv::Scalar(0, 160, 0);
  start.markers = true;
  start.thickness = 0;
  start.label = "start";
  PlotOptions top_view;
  top_view.width = 900;
  top_view.height = 800;
  top_view.title = "Trajectory, top view";
  top_view.x_label = "x [m]";
  top_view.y_label = "z [m]";
  top_view.equal_aspect = true;
  std::vector<std::string> written = {JoinPath(dir, "trajectory_xz.png")};
  WritePlotPng(written.back(), {gt_series, est_series, start}, top_view);

  // Error vs segment length: two panels side by side, as the devkit's plots.
  PlotSeries t_series, r_series;
  t_series.color = r_series.color = cv::Scalar(30, 30, 220);
  t_series.markers = r_series.markers = true;
  t_series.label = "t_rel (" + std::string(metrics.align == AlignmentMode::kNone ? "raw" : AlignmentModeName(metrics.align)) + ")";
  r_series.label = "r_rel (" + std::string(metrics.align == AlignmentMode::kNone ? "raw" : AlignmentModeName(metrics.align)) + ")";
  for (const SegmentLengthErrors& b : metrics.per_length) {
    if (b.segments == 0) continue;
    t_series.x.push_back(b.length);
    t_series.y.push_back(b.t_rel);
    r_series.x.push_back(b.length);
    r_series.y.push_back(b.r_rel);
  }
  const std::string segment_path = JoinPath(dir, "segment_errors.png");
  if (t_series.x.empty()) {
    // No segments: nothing to plot (the caller says why), and a plot of an earlier run in this folder
    // must not stay beside this run's top view as if it were this run's.
    std::error_code error;
    std::filesystem::remove(segment_path, error);  // no error when there is no such file
    RequireFile(!error, segment_path, "cannot remove the segment-error plot of an earlier run: " + error.message());
    return written;
  }
  PlotOptions panel;
  panel.width = 650;
  panel.height = 500;
  panel.include_zero_y = true;
  panel.x_label = "segment length [m]";
  panel.title = "Translation error";
  panel.y_label = "t_rel [%]";
  const cv::Mat t_image = RenderPlot({t_series}, panel);
  panel.title = "Rotation error";
  panel.y_label = "r_rel [deg/100 m]";
  const cv::Mat r_image = RenderPlot({r_series}, panel);
  cv::Mat both;
  cv::hconcat(t_image, r_image, both);
  WriteImageAtomically(segment_path, both);
  written.push_back(segment_path);
  return written;
}

}  // namespace dvso
