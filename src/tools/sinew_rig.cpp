// sinew-rig FILE: what a rigged character file holds (meshes with their closedness and bones, the node
// hierarchy with the joints that move skin, the animation clips), read as Sinew reads it (Assimp), so
// that a user can choose what a scene names. Exit codes as sinew's: 0, 2 bad command line, 3 bad input.
#include <sinew/core/errors.hpp>
#include <sinew/discretization/rig_file.hpp>

#include <iostream>
#include <string>

int main(int argc, char** argv) {
  if (argc != 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help") {
    (argc == 2 ? std::cout : std::cerr) << "usage: sinew-rig FILE   (glTF, FBX, COLLADA, DirectX .x, BVH, ... as Assimp reads them)\n";
    return argc == 2 ? 0 : 2;
  }
  try {
    std::cout << sinew::describe(sinew::read_rig_file(argv[1]));
    return 0;
  } catch (const sinew::InputError& e) {
    std::cerr << "sinew-rig: " << e.what() << "\n";
    return 3;
  }
}
