#pragma once
// A guard in front of PCL's PLY and PCD readers. PCL 1.13 trusts the counts in a file's header and allocates what
// they claim before it reads the data: a PLY "element vertex -1" asks for ~4 G vertices (gigabytes, then
// std::bad_alloc or the OOM killer), and an empty PCD file makes PCDReader::read dereference a null mapping. Found by
// fuzzing LoadPointCloud (tests/fuzz, docs/testing.md).
#include <string>

#include "core/util/status.hpp"

namespace rotolidar {

/// Checks the header of the PLY or PCD file at `path` (by extension, any case: .ply or .pcd) against its size.
/// Ok when the file is not empty and every element / point count is a whole number >= 0 whose data fits in the
/// bytes after the header (binary: count x the element's size in bytes; ASCII: at least one byte per value;
/// compressed PCD: LZF expands at most ~100x), every header line is one this check understands (PCL skips the
/// others and then misreads the file), and a PCD carries x, y, z as single 4-byte floats (what pcl::PointXYZ
/// reads). Otherwise an error naming the file, the header line (1-based) and the field.
Status CheckPointCloudHeader(const std::string& path);

}  // namespace rotolidar
