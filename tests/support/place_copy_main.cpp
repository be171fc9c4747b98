// place_copy FILE DX DY DZ: prints FILE's model moved by (DX, DY, DZ) metres (see
// placed_copy.hpp), for bench/fig9.sh's second copy of a robot.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "placed_copy.hpp"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s FILE DX DY DZ (metres)\n", argv[0]);
    return 1;
  }
  try {
    std::fputs(afhub::testing::placed_copy(argv[1], std::atof(argv[2]), std::atof(argv[3]),
                                           std::atof(argv[4]))
                   .c_str(),
               stdout);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 1;
  }
  return 0;
}
