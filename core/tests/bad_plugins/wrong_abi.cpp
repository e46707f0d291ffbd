// A plugin built for another plugin ABI.
#include <fba/plugin.hpp>
extern "C" [[gnu::visibility("default")]] const fba::PluginInfo fba_plugin_info = {fba::kPluginMagic, 999, "wrong_abi", "9.9.9",
                                                                                   FBA_BUILD_ABI_TAG};
