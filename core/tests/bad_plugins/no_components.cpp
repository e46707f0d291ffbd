// A valid plugin record with no component in it.
#include <fba/plugin.hpp>
FBA_PLUGIN("no_components")
