// LabelProducer: the per-frame work of the label writer — render the final
// points into the frame (label_map.h), verify the labels on the frame's own
// stereo pair (stereo_check.h), write the PNG atomically and hand the map to
// a sink — either right away or on one worker thread, so that label
// extraction overlaps the odometry (which then only waits when the worker
// falls `max_queue` frames behind). Frames are produced in submission order.
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/camera.h"
#include "sdso_labels/label_map.h"
#include "sdso_labels/stereo_check.h"

namespace dvso::labels {

// Receives each finished label map (frame index, CV_32F disparity map).
using LabelSink = std::function<void(int frame_index, const cv::Mat& labels)>;
// Loads the rectified grey pair of a frame (for the stereo check). With a
// worker thread it is called from that thread.
using StereoPairLoader = std::function<void(int frame_index, cv::Mat* left, cv::Mat* right)>;

// Counters of the label extraction (for summaries and tuning).
struct LabelCounters {
  long frames = 0;
  long projected = 0;      // labels after projection and occlusion/edge handling
  long verified = 0;       // labels kept by the stereo check (= written)
  long right_projected = 0, right_verified = 0;  // the same for right-image labels
  double extract_ms = 0;   // projection + stereo check
  double check_ms = 0;     // the stereo check alone (part of extract_ms)
  double write_ms = 0;     // PNG encoding and writing
};

// One frame to label: the final points and the frame's final pose (none: an empty map).
struct LabelJob {
  int frame_index = 0;
  bool has_pose = false;
  Eigen::Isometry3d T_world_frame = Eigen::Isometry3d::Identity();
  std::vector<LabelPoint> points;
};

struct LabelProducerOptions {
  LabelProjectionOptions projection;  // rendering of the points
  StereoCheckOptions stereo_check;    // verification on the frame's pair (needs a loader)
  bool overwrite = false;             // rewrite existing label files (else keep them: resume)
  // Also label the right image (paper section 3.2: L_s uses Omega_DSO of both images):
  // the same points seen from the right camera, verified on the mirrored pair,
  // written to out_dir/right/%06d.png.
  bool right_labels = false;
  bool worker_thread = false;         // produce on a worker thread
  int max_queue = 4;                  // frames waiting for the worker before Submit blocks

  void Check() const;
};

class LabelProducer {
 public:
  // `right_sink` gets the right-image maps (with options.right_labels).
  LabelProducer(const StereoCamera& camera, const LabelProducerOptions& options, std::string out_dir,
                LabelSink sink, StereoPairLoader loader, LabelSink right_sink = {});

  // Where frame `index`'s label file goes (right = the right image's).
  static std::string LabelPath(const std::string& out_dir, int frame_index, bool right = false);
  ~LabelProducer();  // waits for the worker (errors are dropped here: call Finish to see them)
  LabelProducer(const LabelProducer&) = delete;
  LabelProducer& operator=(const LabelProducer&) = delete;

  // Produces the frame now, or queues it for the worker (blocks while the
  // queue is full). Rethrows an error the worker met on an earlier frame.
  void Submit(LabelJob job);
  // Waits until every submitted frame is written; rethrows a worker error.
  void Finish();

  int frames_written() const { return frames_written_; }
  // Complete once Finish() returned (the worker updates them while running).
  const LabelCounters& counters() const { return counters_; }

 private:
  void Produce(const LabelJob& job);
  // Renders (and verifies) one side's map; `right` selects the right camera.
  cv::Mat Render(const LabelJob& job, bool right, const cv::Mat& left_image, const cv::Mat& right_image);
  void WriteMap(const std::string& path, const cv::Mat& labels);
  void WorkerLoop();
  void RethrowWorkerError();

  StereoCamera camera_;
  LabelProducerOptions options_;
  std::string out_dir_;
  LabelSink sink_;
  StereoPairLoader loader_;
  LabelSink right_sink_;
  LabelCounters counters_;
  std::atomic<int> frames_written_{0};

  std::thread worker_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<LabelJob> queue_;  // guarded by mutex_
  bool busy_ = false;           // the worker is producing a job (guarded by mutex_)
  bool stop_ = false;           // guarded by mutex_
  std::exception_ptr error_;    // guarded by mutex_
};

}  // namespace dvso::labels
