// Binding a property value written in a SAD, DCD or SPD (simpleref, structref, ...) to its PRF
// definition: the id must exist, the form must match, and every value must fit its type and range.
#pragma once

#include "common/diagnostic.hpp"
#include "profile/prf.hpp"
#include "profile/property_refs.hpp"

namespace rsca::profile {

// The typed value of `ref` under `definition`. Errors are located at the ref.
Expected<PropertyValue> bind_property(const PropertyDefinition &definition, const PropertyRef &ref);

// Whether `ref` sets a simple property that is not a string to the empty text: REDHAWK takes
// that as no override (the property keeps its value), and so does rsca, with a warning.
bool is_empty_override(const PropertyDefinition &definition, const PropertyRef &ref);
bool is_empty_override(const SimpleProperty &definition, const PropertyRef &ref);

// Whether binding failed only because the override names struct members the PRF does not
// define: REDHAWK warns and ignores such an override, as one of a property the PRF lacks.
bool names_unknown_members_only(const Error &binding);

} // namespace rsca::profile
