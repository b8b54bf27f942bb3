// Placeholder: being written (M1 work in progress).
#include <iostream>

#include "bench/cli/commands.hpp"

namespace rotolidar::bench {

int CmdBench(int, char**) {
  std::cerr << "error: 'rotolidar bench' is not built yet\n";
  return 1;
}

}  // namespace rotolidar::bench
