// Where rsca's programs find the rest of rsca: its loadable libraries (the XML reader module, the
// shared-library components), the example components' programs and the default profiles. Two
// layouts are known, both found from the running program's folder so that either may be moved
// whole: an installed tree (GNUInstallDirs: bin/, lib/<arch>/rsca/, libexec/rsca/,
// share/rsca/profiles/) and the build tree (bin/, lib/, and the source's profiles/).
#pragma once

#include <filesystem>
#include <vector>

namespace rsca::layout {

// Folders that may hold rsca's loadable libraries, the installed one first.
std::vector<std::filesystem::path> library_folders();
// Folders that may hold component code an SPD names: the program's own folder, the installed
// libexec folder, then the library folders.
std::vector<std::filesystem::path> component_folders();
// The default SDR root: the installed profiles when this program is installed, else the
// source tree's beside the build tree. Empty when neither is there.
std::filesystem::path default_sdrroot();

} // namespace rsca::layout
