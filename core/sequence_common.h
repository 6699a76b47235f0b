// Internal helpers shared by the sequence readers (not part of the public API).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dvso::internal {

// Loads an image as CV_8UC1 grey (colour is converted); throws dvso::Error
// naming the file when missing/undecodable or not of the expected size
// (expected size 0x0 = no check). 16-bit images are scaled to 8 bit.
cv::Mat LoadGreyImage(const std::string& path, cv::Size expected = {});
// Loads an image as CV_8UC3 (BGR); same checks.
cv::Mat LoadColorImage(const std::string& path, cv::Size expected = {});
// Image files (png, jpg, jpeg, pgm, bmp; any case; hidden ones left out) of a directory in natural order: digit runs compare
// as numbers, so 1.png 2.png 10.png stay in that order (zero-padded KITTI names sort as before), and
// digits after a decimal point as a fraction (timestamps as names: 100.25 before 100.3).
std::vector<std::string> ListImages(const std::string& directory);
// Frames numbered by their names (KITTI: frame i is %06d.png). When every file's stem is a number of
// one width with one extension: the path the first missing number would have, counting from 0 (a
// missing first frame too) up to the highest number, or to `count` - 1 when `count` (times.txt's length)
// is larger; "" when nothing is missing or the list is not one numbering. A missing image would shift
// every later frame onto another timestamp and pose. When there are exactly `count` files, the count
// starts at the first file's number instead: a clip that kept its frame numbers (001000..001029) with
// its own 30 times.
std::string FirstMissingNumberedFrame(const std::vector<std::string>& files, size_t count = 0);
// Natural order of two file names (ListImages).
bool NaturalLess(const std::string& a, const std::string& b);
// The size of the first of `files` that decodes (up to kSizeProbeFrames of them): a damaged first
// frame is a lost frame of the run, not a sequence that cannot be opened. Throws dvso::Error naming
// the first file when none of them decodes.
inline constexpr int kSizeProbeFrames = 10;
cv::Size FirstDecodableImageSize(const std::vector<std::string>& files);
// Throws dvso::Error naming `calibration` when the images are not of the size it gives: a mismatch
// would otherwise make every frame unreadable, one warning at a time.
void RequireImagesOfCalibratedSize(const std::vector<std::string>& files, cv::Size calibrated,
                                   const std::string& calibration);
// Where the camera of a rectified 3x4 projection matrix (row-major, 12 numbers, KITTI's P = K [I | t] in
// rectified camera 0) sits: t = K^-1 P[:, 3] (metres), so t.z = P[2][3] and t.x = (P[0][3] - cx t.z) / fx for
// KITTI's K. KITTI's colour cameras have t.y and t.z of a few mm besides t.x. The one reading of a camera's
// offset: RectifiedBaseline and CameraFromImu (kitti_oxts.h) both use it. Throws dvso::Error naming
// `calibration` (the file the matrix came from) on a singular K.
cv::Vec3d RectifiedCameraOffset(const std::vector<double>& projection, const std::string& calibration);
// The baseline (metres) of a rectified pair from its two projection matrices: b = t_left.x - t_right.x
// (RectifiedCameraOffset). Leaving out t.z, as P[0][3] / fx does, would make KITTI's colour baseline (and every
// metric scale from it) ~0.2 % short.
double RectifiedBaseline(const std::vector<double>& p_left, const std::vector<double>& p_right,
                         const std::string& calibration);
// Throws dvso::Error naming `calibration` when the principal point of `camera` lies outside its images (a
// calibration made for another image size: a full-size KITTI calib.txt beside downscaled images), and warns
// on stderr when it lies off the centre by more than kPrincipalPointWarnOffset of the size, which a
// calibration for images twice the size gives: intrinsics scaled with the images are the user's job,
// and a wrong camera otherwise runs to a garbage trajectory without any error.
inline constexpr double kPrincipalPointWarnOffset = 0.25;
void CheckPrincipalPointFitsImages(double cx, double cy, int width, int height, const std::string& calibration);
// Throws dvso::Error naming files[first] when the 16-bit images files[first, end) (the probe frames) all stay
// below 2^12 in every colour channel (a 12-bit sensor's or an 8-bit image's values in a 16-bit PNG): read as
// the full 16-bit range, as the readers do, they would be nearly black and every frame lost without a word.
// One dark frame (a lens cap, a tunnel) among full-range ones passes. FirstDecodableImageSize calls it.
inline constexpr int kMinSixteenBitMaximum = 1 << 12;
void RequireSixteenBitRange(const std::vector<std::string>& files, size_t first, size_t end);
// Whether two rectified 3x4 projection matrices (row-major, 12 numbers, KITTI's P = K [I | t]) describe the
// same camera: equal intrinsics and centre. On KITTI the colour cameras sit ~6 cm beside the grey ones
// (P2[0][3] != P0[0][3]), so their images are another viewpoint; our simulator renders colour at the grey centres.
bool SameRectifiedCamera(const std::vector<double>& p, const std::vector<double>& q);
// The one rule for "the colour pair is the grey pair in colour" (KITTI odometry calib.txt and raw
// calib_cam_to_cam.txt alike): the left colour camera is the left grey one, and a right colour camera, when
// there is one to read (nullptr = none), is the right grey one (grey_right nullptr = no right grey camera).
bool ColourPairMatchesGrey(const std::vector<double>& grey_left, const std::vector<double>* grey_right,
                           const std::vector<double>& colour_left, const std::vector<double>* colour_right);

}  // namespace dvso::internal
