// Runs the odometry over a stored sequence, streaming frames (one in memory at
// a time), and writes the outputs of `dvso odometry` into a directory:
//   trajectory.txt      KITTI 3x4 camera-to-world, one line per processed frame, input order
//   trajectory_tum.txt  TUM "t x y z qx qy qz qw"
//   run_log.csv         per frame: status, timings, window sizes, virtual stereo residuals
//   points.ply          marginalised points (optional)
//   config.yaml         the options used
//   INTERRUPTED         only when the run was stopped by SIGINT/SIGTERM: the
//                       other files then hold the frames processed until then
#pragma once

#include <string>
#include <vector>

#include "core/disparity_source.h"
#include "core/sequence.h"
#include "vo/system/observer.h"
#include "vo/system/odometry_options.h"

namespace dvso::vo {

struct SequenceRunOptions {
  int first = 0;              // first frame index to process
  int count = -1;             // number of frames (-1 = to the end)
  bool write_ply = false;     // write points.ply
  bool progress = true;       // progress bar on stderr
  std::vector<OdometryObserver*> extra_observers;  // non-owning, e.g. the label writer of sdso_labels
  DisparitySource* predictions = nullptr;          // non-owning; required by modes with predictions (DVSO)
  bool strict = false;        // an unreadable image stops the run with its error (default: warn, count, go on)
  bool stop_on_interrupt = false;  // SIGINT / SIGTERM end the run after the current frame; outputs are written
  void Check() const;
};

struct SequenceRunSummary {
  int frames = 0;
  int keyframes = 0;
  int tracked = 0;            // frames tracked or made keyframes (a stereo run's first frame too)
  int lost = 0;               // frames reported lost
  int initializing = 0;       // frames before (re-)initialisation finished
  int resets = 0;             // re-initialisations after a loss
  int unreadable = 0;         // frames whose image could not be read (counted as lost)
  bool interrupted = false;   // stopped by SIGINT / SIGTERM before the last frame
  double mean_ms = 0;         // mean total time per frame (excl. image loading)
  double wall_ms = 0;         // wall time per frame of the whole loop (incl. image loading)
  double max_ms = 0;
  long ply_points = 0;
};

SequenceRunSummary RunOdometryOnSequence(const SequenceReader& sequence, const OdometryOptions& options,
                                         OdometryMode mode, const std::string& out_dir,
                                         const SequenceRunOptions& run = {});

}  // namespace dvso::vo
