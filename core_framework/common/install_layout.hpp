// Where rsca's programs find the rest of rsca: its loadable libraries (the XML reader module, the
// shared-library components), the example components' programs and the default profiles. Two
// layouts are known, both found from the running program's folder so that either may be moved
// whole: an installed tree (GNUInstallDirs: bin/, lib/<arch>/rsca/, libexec/rsca/,
// share/rsca/profiles/) and the build tree (bin/, lib/, and the source's profiles/).
#pragma once

#include <filesystem>
#include <vector>

namespace rsca::layout {

// Folders that may hold rsca's loadable libraries: the installed one, or else the build tree's.
std::vector<std::filesystem::path> library_folders();
// Folders that may hold component code an SPD names: the program's own folder, the installed
// libexec folder, then the library folders.
std::vector<std::filesystem::path> component_folders();
// A code file an SPD names (a library, a program): absolute, or relative to the SPD's folder; one
// that is not there is looked up by file name in `folders`. Not found anywhere: where the SPD
// names it, for the error to say.
std::filesystem::path resolve_code(const std::filesystem::path &file,
                                   const std::filesystem::path &spd,
                                   const std::vector<std::filesystem::path> &folders);
// The default SDR root: the installed profiles when this program is installed, else the
// source tree's beside the build tree. Empty when neither is there.
std::filesystem::path default_sdrroot();

} // namespace rsca::layout
