// A plugin that needs a function nobody defines: dlopen must refuse it by name.
#include <fba/plugin.hpp>
void fba_test_function_nobody_defines();
extern "C" [[gnu::visibility("default")]] void call_it() { fba_test_function_nobody_defines(); }
FBA_PLUGIN("undefined_reference")
