#!/usr/bin/env bash
# Builds the C++ dependencies of `dvso` (all but LibTorch) as static libraries and headers into one prefix and
# packs it for the lent GPU machine (issue 10 item 6), whose image has CUDA PyTorch, CMake, ninja and a compiler
# but no OpenCV, Eigen, yaml-cpp, CLI11 or nlohmann_json development files and no package registry.
# Debian's shared OpenCV drags in ~350 MiB of libraries (GDAL, FFmpeg, Qt, ...) and cannot travel through the
# device's 64 MiB carry limit; a static OpenCV of the four modules `dvso` uses (core, imgproc, imgcodecs with PNG
# only, calib3d) does.
#
#   scripts/gpu/make_bundle.sh            (env: BUNDLE_PREFIX=/opt/dvso-bundle, WORK=/tmp/dvso-bundle-src, JOBS)
#
# Sources come from Debian (`apt-get source`, the project's only package channel) for the versions this machine
# builds against, so the device build sees the same library versions as CI. The prefix is an absolute path
# recorded inside the CMake package files, so the device unpacks the archive to the same place
# (scripts/gpu/train_on_device.sh does). Output: .gpu_bundle/dvso_bundle.tar.xz (ignored by git; carried).
# Idempotent: a finished library is not rebuilt (delete $WORK to start again).
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$(pwd)
BUNDLE_PREFIX=${BUNDLE_PREFIX:-/opt/dvso-bundle}
WORK=${WORK:-/tmp/dvso-bundle-src}
JOBS=${JOBS:-$(nproc)}
mkdir -p "$WORK/lists/partial" "$WORK/cache/archives/partial" "$BUNDLE_PREFIX"

# A private source list: the machine's own apt configuration has no deb-src lines and is not ours to change.
. /etc/os-release
echo "deb-src http://deb.debian.org/debian ${VERSION_CODENAME} main" > "$WORK/sources.list"
APT=(apt-get -o Dir::Etc::SourceList="$WORK/sources.list" -o Dir::Etc::SourceParts=/dev/null
     -o Dir::State::Lists="$WORK/lists" -o Dir::Cache="$WORK/cache" -o Debug::NoLocking=1)
[[ -f "$WORK/lists.done" ]] || { "${APT[@]}" update -q && touch "$WORK/lists.done"; }

source_dir() {  # source_dir PACKAGE -> prints the unpacked source folder (downloads it once)
  local pkg=$1
  if ! ls -d "$WORK/src-$pkg"/*/ >/dev/null 2>&1; then
    mkdir -p "$WORK/src-$pkg"
    (cd "$WORK/src-$pkg" && "${APT[@]}" source -q "$pkg" >/dev/null)
  fi
  ls -d "$WORK/src-$pkg"/*/ | head -1
}

cmake_install() {  # cmake_install PACKAGE [CMAKE ARGS...]: configure, build and install into the prefix once
  local pkg=$1; shift
  [[ -f "$WORK/$pkg.done" ]] && { echo "bundle: $pkg already built"; return; }
  local src; src=$(source_dir "$pkg")
  echo "bundle: building $pkg from $src"
  cmake -S "$src" -B "$WORK/build-$pkg" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$BUNDLE_PREFIX" \
    -DCMAKE_PREFIX_PATH="$BUNDLE_PREFIX" -DCMAKE_POSITION_INDEPENDENT_CODE=ON -DBUILD_SHARED_LIBS=OFF "$@" >/dev/null
  cmake --build "$WORK/build-$pkg" -j "$JOBS" >/dev/null
  cmake --install "$WORK/build-$pkg" >/dev/null
  touch "$WORK/$pkg.done"
}

# zlib and libpng: Debian's own static archives (zlib1g-dev, libpng-dev; compiled position-independent like all of
# Debian) and their headers, copied; their CMake builds would add nothing but a shared library to remove.
mkdir -p "$BUNDLE_PREFIX/lib" "$BUNDLE_PREFIX/include"
MULTIARCH=$(gcc -print-multiarch)
cp "/usr/lib/$MULTIARCH/libz.a" "/usr/lib/$MULTIARCH/libpng16.a" "$BUNDLE_PREFIX/lib/"
cp /usr/include/zlib.h "/usr/include/$MULTIARCH/zconf.h" /usr/include/libpng16/png.h /usr/include/libpng16/pngconf.h \
  /usr/include/libpng16/pnglibconf.h "$BUNDLE_PREFIX/include/" 2>/dev/null ||
  cp /usr/include/zlib.h /usr/include/zconf.h /usr/include/libpng16/png*.h "$BUNDLE_PREFIX/include/"
cmake_install eigen3 -DBUILD_TESTING=OFF -DEIGEN_BUILD_DOC=OFF -DEIGEN_BUILD_PKGCONFIG=OFF
cmake_install cli11 -DCLI11_BUILD_TESTS=OFF -DCLI11_BUILD_EXAMPLES=OFF -DCLI11_BUILD_DOCS=OFF
cmake_install nlohmann-json3 -DJSON_BuildTests=OFF
cmake_install yaml-cpp -DYAML_CPP_BUILD_TESTS=OFF -DYAML_CPP_BUILD_TOOLS=OFF -DYAML_CPP_BUILD_CONTRIB=OFF
# OpenCV: the four modules and their dependencies (calib3d needs features2d and flann), PNG through the bundle's
# libpng, nothing that would need another library or a download (Debian's source has no 3rdparty/ folder).
cmake_install opencv -DBUILD_LIST=core,imgproc,imgcodecs,calib3d -DWITH_PNG=ON -DBUILD_PNG=OFF -DBUILD_ZLIB=OFF \
  -DPNG_LIBRARY="$BUNDLE_PREFIX/lib/libpng16.a" -DPNG_PNG_INCLUDE_DIR="$BUNDLE_PREFIX/include" \
  -DZLIB_LIBRARY="$BUNDLE_PREFIX/lib/libz.a" -DZLIB_INCLUDE_DIR="$BUNDLE_PREFIX/include" \
  -DWITH_JPEG=OFF -DWITH_TIFF=OFF -DWITH_WEBP=OFF -DWITH_OPENJPEG=OFF -DWITH_JASPER=OFF -DWITH_OPENEXR=OFF \
  -DWITH_IMGCODEC_HDR=OFF -DWITH_IMGCODEC_SUNRASTER=OFF -DWITH_IMGCODEC_PXM=OFF -DWITH_IMGCODEC_PFM=OFF \
  -DWITH_GDAL=OFF -DWITH_GDCM=OFF -DWITH_FFMPEG=OFF -DWITH_GSTREAMER=OFF -DWITH_V4L=OFF -DWITH_GTK=OFF -DWITH_QT=OFF \
  -DWITH_IPP=OFF -DWITH_ITT=OFF -DWITH_OPENCL=OFF -DWITH_LAPACK=OFF -DWITH_EIGEN=OFF -DWITH_TBB=OFF -DWITH_OPENMP=OFF \
  -DWITH_PROTOBUF=OFF -DWITH_QUIRC=OFF -DWITH_ADE=OFF -DWITH_VA=OFF -DWITH_VA_INTEL=OFF -DWITH_1394=OFF \
  -DWITH_CUDA=OFF -DWITH_VTK=OFF -DWITH_HALIDE=OFF -DWITH_ONNX=OFF -DWITH_CAROTENE=OFF -DWITH_KLEIDICV=OFF \
  -DBUILD_TESTS=OFF -DBUILD_PERF_TESTS=OFF -DBUILD_EXAMPLES=OFF -DBUILD_DOCS=OFF -DBUILD_opencv_apps=OFF \
  -DBUILD_JAVA=OFF -DBUILD_opencv_python3=OFF -DBUILD_opencv_python2=OFF -DOPENCV_GENERATE_PKGCONFIG=OFF \
  -DCPU_DISPATCH= -DOPENCV_SKIP_PYTHON_LOADER=ON

mkdir -p "$REPO/.gpu_bundle"
rm -rf "$BUNDLE_PREFIX/share/doc" "$BUNDLE_PREFIX/share/licenses"
tar -C / -cJf "$REPO/.gpu_bundle/dvso_bundle.tar.xz" "${BUNDLE_PREFIX#/}"
echo "bundle: $(du -h "$REPO/.gpu_bundle/dvso_bundle.tar.xz" | cut -f1) in .gpu_bundle/dvso_bundle.tar.xz (prefix $BUNDLE_PREFIX)"
