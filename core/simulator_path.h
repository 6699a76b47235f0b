// The driving path of the synthetic world: camera poses (from a KITTI pose
// file or generated), resampled by arc length into a street centre line with a
// local frame and road height per sample, plus the street's cross-section
// profile (lane, road edges, sidewalks) along it. Objects are placed relative
// to this line, and a spatial hash answers "is this point on some street?" so
// that loops and crossings of the path never get a building in the road.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dvso::sim {

// Cross-section of the street at one sample; lateral offsets are metres to the
// right of the camera path (negative = left).
struct StreetProfile {
  double left_edge = -5.5;     // left road edge (curb)
  double right_edge = 2.0;     // right road edge (curb)
  double sidewalk_left = 2.5;  // sidewalk width beyond the left curb
  double sidewalk_right = 2.5; // sidewalk width beyond the right curb
  bool parking_left = false;   // parking lane along the left curb
  bool parking_right = false;  // parking lane along the right curb
  bool green = false;          // verge of grass (else paved / dirt) and more trees
  int section = 0;             // index of the street section (seeds its objects)
};

struct PathSample {
  Eigen::Vector3d road;     // road surface point below the camera path (world)
  Eigen::Vector3d tangent;  // horizontal unit driving direction
  Eigen::Vector3d right;    // horizontal unit vector to the right (down x tangent)
  double s = 0;             // arc length (m, horizontal), 0 at the first pose
  StreetProfile profile;
  // >= 0 when this part of the path drives again along an earlier part of
  // the same street (a revisit): the sample then builds no street or objects
  // of its own; the earlier sample's street is widened to hold its lane.
  int merged_into = -1;
};

// Where a point may lie relative to the streets (for object placement).
enum class Zone {
  kLane,    // within +-1.6 m of a camera path (would be driven through)
  kRoad,    // between the curbs of some street
  kStreet,  // road or sidewalk of some street
};

// Point indices bucketed by horizontal position (the plane across `down`) in square cells of
// `cell_size` m: the one neighbour search of the street path and of the altitude pairs.
class HorizontalGrid {
 public:
  HorizontalGrid() = default;  // empty; assign a constructed grid before use (StreetPath's member)
  HorizontalGrid(const Eigen::Vector3d& down, double cell_size);
  void Insert(const Eigen::Vector3d& q, int index);
  double cell_size() const { return cell_size_; }
  // Calls visit(index) for the points of q's cell and of the eight around it, in a fixed order
  // (cells, then insertion), until visit returns true; returns whether one did. Every point within
  // cell_size of q horizontally is visited (and some farther ones: callers test the distance).
  template <typename Visit>
  bool AnyNear(const Eigen::Vector3d& q, Visit&& visit) const {
    const std::pair<int, int> cell = CellOf(q);
    for (int da = -1; da <= 1; ++da)
      for (int db = -1; db <= 1; ++db) {
        const auto it = cells_.find(Key(cell.first + da, cell.second + db));
        if (it == cells_.end()) continue;
        for (int index : it->second)
          if (visit(index)) return true;
      }
    return false;
  }

 private:
  std::pair<int, int> CellOf(const Eigen::Vector3d& q) const;
  // Hash key of a cell (no signed shifts: cells can be negative).
  static int64_t Key(int a, int b) {
    return static_cast<int64_t>((static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b));
  }
  Eigen::Vector3d axis_a_ = Eigen::Vector3d::UnitX(), axis_b_ = Eigen::Vector3d::UnitZ();  // horizontal basis
  double cell_size_ = 1.0;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

// m of arc length: path samples at least this far apart along the path are different passes of
// one place (a loop, a revisit, a crossing); closer ones belong to the same pass.
constexpr double kRevisitMinArcGap = 60.0;
// m: a sample within this of an earlier pass (horizontally, driving parallel or anti-parallel)
// drives on that pass's street (StreetPath::MergeRevisits): its lane, +-2 m, fits on that road.
constexpr double kRevisitMergeRadius = 4.0;
// m: an invented street beyond the path's ends yields where it comes this close to the driven
// path (StreetPath::DropExtensionsOverThePath): a road and its sidewalks, as far as the altitude
// reconciliation's radius (AltitudeReconciliationOptions::radius) counts two passes as one street.
constexpr double kExtensionYieldRadius = 12.0;

class StreetPath {
 public:
  // poses: camera-to-world of every frame of the trajectory (KITTI convention:
  // camera y points down). spacing: metres between samples. extension: metres
  // of straight street added before the first and after the last pose.
  StreetPath(const std::vector<Eigen::Isometry3d>& poses, double camera_height, double spacing,
             double extension);

  // World "down" direction (mean camera y axis of the trajectory).
  const Eigen::Vector3d& down() const { return down_; }
  const std::vector<PathSample>& samples() const { return samples_; }
  std::vector<PathSample>& mutable_samples() { return samples_; }
  double spacing() const { return spacing_; }
  // Arc length (m) of the camera centre of pose i.
  double PoseArcLength(int i) const { return pose_s_[i]; }
  // Index of the sample nearest to arc length s (clamped).
  int SampleAt(double s) const;
  // Marks revisits (samples within `radius` m of an earlier sample at least
  // `min_gap` m of arc length before, driving parallel or anti-parallel) as
  // merged and widens the earlier sample's road to contain their lane.
  // radius <= 12 m (the grid's cell).
  void MergeRevisits(double radius, double min_gap);
  // The straight streets added before the first and after the last pose are invented: where one
  // runs within `radius` m of a sample of the driven path at least `min_gap` m of arc length away
  // (a loop: KITTI 06's street before its start runs through its frames 750-790, 00's after its end
  // through its start), its samples are marked merged into that sample and build nothing. Else
  // they were laid at the first or last pose's height through the driven street, and a later pass
  // merged into them drove with the camera up to 0.7 m below its height above the road. Whatever
  // the two streets' directions or heights (a crossing, a bridge): an invented street never
  // outranks a driven one. Call before MergeRevisits. radius <= 12 m (the grid's cell).
  void DropExtensionsOverThePath(double radius, double min_gap);

  // Vertical clearance (m) between an object and a street at another level:
  // a street whose road lies more than this above the object's top or below
  // its bottom passes over or under it (a bridge), so it does not count.
  static constexpr double kLevelClearance = 4.0;

  // True when the horizontal position of q lies in `zone` of any sample
  // (grown by margin metres). Merged samples count only for Zone::kLane.
  // The object stands from q up to q + object_height: on a hill the same
  // street climbs past a tall building, so a sample counts whenever its road
  // comes within kLevelClearance of that vertical extent, not only of q.
  bool InZone(const Eigen::Vector3d& q, Zone zone, double margin, double object_height = 0.0) const;
  // InZone for a point on the street itself (no height), not counting the
  // samples with index in [ignore_begin, ignore_end): the street's own
  // neighbourhood, when asking whether another street crosses there.
  bool InZoneOfOtherSamples(const Eigen::Vector3d& q, Zone zone, double margin, int ignore_begin,
                            int ignore_end) const;

 private:
  bool AnySampleZoneContains(const Eigen::Vector3d& q, Zone zone, double margin, int ignore_begin, int ignore_end,
                             double object_height) const;
  // m: cell of the samples' grid; MergeRevisits' and DropExtensionsOverThePath's radius may not exceed it.
  static constexpr double kGridCellSize = 12.0;
  Eigen::Vector3d down_;
  double spacing_;
  std::vector<PathSample> samples_;
  std::vector<double> pose_s_;
  HorizontalGrid grid_;  // samples by their road point
};

// Recorded trajectories drift in altitude (KITTI's ground truth comes from GPS/IMU): where a path
// crosses itself or drives a street again, the passes disagree by up to metres vertically (KITTI
// 00: median 0.45 m, 02: 1.6 m, 08: 2.7 m between points within 8 m, docs/simulator.md). The
// simulator lays ONE street per place, so without a correction a revisit drives with the camera
// up to 2 m above or below the road it sees (a merged revisit reuses the earlier street) and
// crossings get steps and slots through which the ground's underside shows.
// Weight of the pull of every correction towards 0 in AltitudeCorrections: it only fixes the
// offset and tilt that the pairs and the second differences leave free.
constexpr double kAltitudeAnchorWeight = 1e-3;
// A pose whose neighbours are closer than this (m, horizontally) stands still: its direction of
// travel is taken from the camera's viewing direction instead.
constexpr double kStandingStillDistance = 0.05;

struct AltitudeReconciliationOptions {
  double radius = 12.0;         // m: path points this close horizontally share road or sidewalk
  double min_gap = kRevisitMinArcGap;  // m of arc length between them (closer = the same pass)
  // m: passes farther apart vertically are different levels (a bridge deck is >= ~5 m above the
  // road below it); above KITTI 08's largest drift between passes (6.4 m).
  double max_difference = 8.0;
  // Weight of the correction's second differences (samples 2 m apart; a pair of passes weighs
  // 1 - distance / radius). 3000: the slope the correction adds stays <= 1.2 % at 99 % of the
  // samples of KITTI 00, 05, 06, 07, 09; 02 drifts 7 m and gets up to 6 % over long stretches,
  // 08 (two passes whose altitudes drift apart by 4 m over 160 m) up to 13 % in places.
  double smoothness = 3000.0;
  double spacing = 2.0;         // m between the samples the correction is solved on

  void Check() const;
};

// Mean camera "down" axis of a trajectory (camera y axis, KITTI convention), unit length.
Eigen::Vector3d TrajectoryDown(const std::vector<Eigen::Isometry3d>& poses);

// The correction of one pose: offset (m along `down`) and its rate along the path, d offset /
// d arc length (the change of the road's slope there).
struct AltitudeCorrection {
  double offset = 0;
  double slope = 0;
};

// Per-pose altitude correction c_i minimising
//   sum_pairs w_kl (h_k + c_k - h_l - c_l)^2 + smoothness * sum_k (c_{k-1} - 2 c_k + c_{k+1})^2
//   + kAltitudeAnchorWeight * sum_k c_k^2
// over samples every `spacing` m of arc length (h = height along down; pairs as in the options,
// w = 1 - distance / radius), interpolated linearly to the poses (the slope from central
// differences). A path that never comes back to a place gets zero corrections exactly.
std::vector<AltitudeCorrection> AltitudeCorrections(const std::vector<Eigen::Isometry3d>& poses,
                                                    const AltitudeReconciliationOptions& options);

// Moves pose i by offset_i * down and pitches it by atan(slope_i) about the horizontal axis across
// its direction of travel (that direction towards down where the offset grows along the path), so
// that the camera keeps its attitude relative to the corrected road: a correction spread over a
// long stretch tilts the road by up to a few per cent (KITTI 02), which a camera left level would
// see as a horizon shifted by f_x * slope pixels.
void ApplyAltitudeCorrections(const std::vector<AltitudeCorrection>& corrections,
                              std::vector<Eigen::Isometry3d>* poses);

// A smooth, KITTI-like driving path (straights, turns of 15-60 m radius, gentle
// hills, ~10 m/s at 10 Hz, small pitch/roll vibrations), camera-to-world, first
// pose = identity, camera y down.
std::vector<Eigen::Isometry3d> GenerateDrivingPath(int num_poses, double speed, double frame_interval,
                                                   uint64_t seed);

}  // namespace dvso::sim
