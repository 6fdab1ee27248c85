# Reproducible results: svbtdf's programs, tests and Python module load the reference BLAS and
# LAPACK (Debian's libblas3 and liblapack3), whatever the system's alternative for
# libblas.so.3 / liblapack.so.3 is.
#
# Why: ATLAS (which Debian picks when it is installed, as OpenCV's and Ceres's dependencies bring
# it) chooses its kernels' code paths by the alignment of the memory it is handed. OpenCV's
# camera calibration goes through LAPACK, so calibrating one session twice gave focal lengths
# differing in the 10th digit whenever the two runs' heaps differed (the session at a longer path,
# a resumed `run`); with the reference libraries the calibrations are bit-identical
# (tests/calib, CalibrationIsBitReproducible...). Nothing hot in svbtdf calls BLAS: its numerics
# are Eigen's, and Ceres solves its small dense problems with Eigen too.
#
# How: an RPATH (not the newer RUNPATH, which the loader does not consult for the dependencies of
# OpenCV's own libraries) listing the reference libraries' folders.
set(svbtdf_reference_blas_dir /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/blas)
set(svbtdf_reference_lapack_dir /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/lapack)
if(EXISTS ${svbtdf_reference_blas_dir}/libblas.so.3 AND EXISTS ${svbtdf_reference_lapack_dir}/liblapack.so.3)
  add_link_options("LINKER:--disable-new-dtags"
                   "LINKER:-rpath,${svbtdf_reference_blas_dir}:${svbtdf_reference_lapack_dir}")
else()
  message(WARNING "The reference BLAS and LAPACK (Debian's libblas3, liblapack3) are not installed: "
                  "calibrations may differ in their last digits from run to run (cmake/ReferenceLinearAlgebra.cmake)")
endif()
