# Every dependency comes from a Debian 12 package (see tools/install_deps.sh).
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
# ximgproc (graph-based segmentation for the plane fit) is in libopencv-contrib-dev, which
# libopencv-dev depends on.
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs calib3d ximgproc)
find_package(yaml-cpp REQUIRED)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(TBB REQUIRED)
find_package(Ceres REQUIRED)
find_package(assimp REQUIRED)
find_package(SuiteSparse REQUIRED)          # cmake/FindSuiteSparse.cmake: 5.x ships no CMake package
find_package(PkgConfig REQUIRED)
pkg_check_modules(MAXFLOW REQUIRED IMPORTED_TARGET maxflow)   # Boykov–Kolmogorov max-flow
# FLANN's k-d tree is header templates (core/nearest_points.cc; libflann-dev comes with
# libpcl-dev); its index-saving code, compiled with it, calls LZ4 (liblz4-dev, a dependency of
# libflann-dev).
pkg_check_modules(LZ4 REQUIRED IMPORTED_TARGET liblz4)
# PCL (and through it VTK) is heavy: ask only for what is used (io: the point-cloud reader;
# registration, filters, kdtree: the scan registration of gcp/sweep_motion.cc; surface: the
# Poisson scene mesh of mesh/surface_reconstruction.cc), and link it privately to the libraries
# that include it.
find_package(PCL 1.10 REQUIRED COMPONENTS common io registration filters kdtree search surface)
if(GCPSTEREO_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(GCPSTEREO_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
