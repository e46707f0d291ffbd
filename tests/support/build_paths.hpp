// Where this build's sources, data (data/) and programs are, for tests and benchmarks.
//
// The paths live in one file CMake generates in the build folder (build_paths.cpp.in), not in
// compile definitions: a definition puts the checkout's absolute path into a compile command, and
// ccache then shares no such object between two checkouts. CI clones into a new folder on every run
// and recompiled every test that named a path (22 to 60 files per build, in each of four builds).
#pragma once

#include <string>

namespace fba::test {

std::string source_dir();       // the checkout
std::string tasks_dir();        // its tasks/
std::string data_dir();         // the images and meshes (FBA_DATA_DIR: the checkout's data/ by default)
std::string binary_dir();       // the build folder
std::string plugin_dir();       // the plugins this build made, where an uninstalled fba-run finds them
std::string program(const std::string& name);  // a program this build made: fba-run, fba-evaluate, ...

}  // namespace fba::test
