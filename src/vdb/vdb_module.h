#pragma once
// The OpenVDB writer as a loadable module (field/animation_export.cpp; docs/architecture.md,
// "What a command loads"): libtvf_vdb.so, built beside the tvf program where OpenVDB was
// found, opened with dlopen() by write_vdb_sequence alone, so that tvf and the Python
// module do not load OpenVDB (and its ~20 libraries) at every start. A C ABI of plain
// arrays: the module and its caller share no C++ type.
#include <cstddef>

extern "C" {

// The version of this ABI; the caller refuses a module with another.
#define TVF_VDB_ABI_VERSION 1
typedef int (*tvf_vdb_abi_version_fn)(void);

// Writes one frame to `path`: a Vec3f grid named "v" whose voxel (ix, iy, 0) holds
// (vectors[3k], vectors[3k + 1], 0), k = iy·nx + ix (3 floats per vertex, the world vectors
// of field/world_vectors.h; z is not read), all nx × ny voxels active; the transform
// maps voxel (ix, iy, 0) to (x0 + ix·hx, y0 + iy·hy, 0) (a linear transform where hx = hy,
// a scale map with z spacing hx otherwise); vector type contravariant-relative; metadata
// "time" = time. Returns 0, or 1 with a sentence in error (error_size bytes, NUL-ended).
typedef int (*tvf_vdb_write_frame_fn)(const char* path, int nx, int ny, double x0, double y0, double hx,
                                      double hy, float time, const float* vectors, char* error, size_t error_size);

int tvf_vdb_abi_version(void);
int tvf_vdb_write_frame(const char* path, int nx, int ny, double x0, double y0, double hx, double hy, float time,
                        const float* vectors, char* error, size_t error_size);
}
