// CodeDescription: what a component's built code declares (its ports and the properties it
// binds), written beside the executable at build time, so that `rsca validate` finds a mismatch
// between the code and its SPD, SCD and PRF before a launch does (issue 39: a misspelled property
// or a port the SCD lacks was found only when the component exited at start).
//
// The SDK's rsca_add_component runs the built executable once with `--rsca-describe FILE`
// (component/runtime.cpp): the component is constructed, as at a launch, and what it declared is
// written, nothing else done. The file is the contract between that run and validate: built and
// read here only, versioned, its sizes bounded (the file sits in a user's folder: untrusted).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"
#include "profile/prf.hpp"
#include "profile/profile_loader.hpp"
#include "profile/scd.hpp"

namespace rsca::profile {

// Beside the executable FILE: FILE.rsca-code.json.
inline constexpr std::string_view kCodeDescriptionSuffix = ".rsca-code.json";
inline constexpr int kCodeDescriptionVersion = 1;

struct CodePort {
  std::string name;
  PortDirection direction = PortDirection::Uses;
  bool resource = false; // calls a component's CF interface (component/resource_port.hpp)
};

struct CodeDescription {
  std::vector<CodePort> ports;
  std::vector<std::string> properties; // the ids it binds
};

std::string to_json_text(const CodeDescription &description);
// A description read back; an error located in `file` when it is not one this version wrote.
Expected<CodeDescription> read_code_description(const std::filesystem::path &file);

// Where a code's description lies, when it does: beside `code`.
std::filesystem::path code_description_path(const std::filesystem::path &code);

// What in the code its profiles do not declare: a port its SCD lacks (by name and direction), a
// property its PRF does not define. The same sentences the component's own start-up check says
// (component/host.cpp), which uses this too.
std::vector<std::string> code_misfits(const CodeDescription &code, const SoftwareComponent *scd,
                                      const std::vector<PropertyDefinition> &definitions);

// The same for each package of `app` whose code lies beside its SPD with a description (a
// component built with the SDK and installed into an SDR root), as errors located at the SPD; a
// description that does not read is one too. Code without a description is not checked.
std::vector<Diagnostic> code_refusals(const ResolvedApplication &app);
std::vector<Diagnostic> code_refusals(const ResolvedSoftPkg &pkg);

} // namespace rsca::profile
