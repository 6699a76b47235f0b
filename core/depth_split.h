// Split files of the KITTI raw depth experiments (monodepth2's splits/ format,
// the paper's Eigen-split evaluation, section 5.1): one image per line,
//   <drive> <frame> <side>      e.g. "2011_09_26/2011_09_26_drive_0002_sync 0000000069 l"
// drive relative to the raw root (date folder / drive folder), frame the file
// number, side l = left colour camera 02, r = right colour camera 03.
// `gt-depth --split` writes one GT map per line named by the line's position
// (%06d.png, 0-based, blank lines and '#' comments not counted), and
// `eval-depth --split` evaluates predictions named the same way (or the rows of
// an .npy stack), so results are in split order as monodepth's gt_depths.npz.
#pragma once

#include <string>
#include <vector>

namespace dvso {

struct SplitEntry {
  std::string drive;  // relative to the raw root, e.g. "2011_09_26/2011_09_26_drive_0002_sync"
  int frame = 0;      // file number of image_0X/data/%010d.png and velodyne_points/data/%010d.bin
  char side = 'l';    // 'l' (camera 02) or 'r' (camera 03)

  int Camera() const { return side == 'l' ? 2 : 3; }
  // "%010d" of frame.
  std::string FrameName() const;
};

// Reads a split file; throws dvso::Error naming the file and line for a line that is not
// "<drive> <frame> <side>" with frame >= 0 and side l or r, and for a file without entries.
std::vector<SplitEntry> ReadSplitFile(const std::string& path);

// File name (without folder) of entry `index`'s map in split order: "%06d.png".
std::string SplitMapName(int index);

}  // namespace dvso
