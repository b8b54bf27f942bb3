#pragma once
// Output files that a reader never sees half-written: write into a temporary name beside the target, then rename
// (atomic on one POSIX file system). Used by snapshots that other programs poll while a run goes on.
#include <filesystem>
#include <string>
#include <system_error>

#include "core/util/status.hpp"

namespace rotolidar::bench {

/// Calls write(part) with part = "<stem>.part<ext>" in path's folder (the extension is kept: writers pick the
/// format by it), then renames part onto path. Fails with write's status or naming both files.
template <class Write>
Status WriteAtomically(const std::string& path, Write write) {
  const std::filesystem::path p(path);
  const std::string part = (p.parent_path() / (p.stem().string() + ".part" + p.extension().string())).string();
  if (Status s = write(part); !s) return s;
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  return ec ? Status::Error(path + ": cannot rename from " + part + ": " + ec.message()) : Status::Ok();
}

}  // namespace rotolidar::bench
