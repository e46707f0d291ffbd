// fba-plugin-manifest: writes a plugin's manifest (what it offers, its ABI record and the layouts
// of its data types) beside it, so fba lists and checks it without running its code. Run at
// build time by fba_add_plugin(); this is the only place where a plugin's code runs unchecked,
// on the machine that built it.
#include <fstream>
#include <iostream>

#include "fba/version.hpp"
#include "plugin_manifest.hpp"

int main(int argc, char** argv) {
  const std::string usage = "usage: fba-plugin-manifest PLUGIN.so [MANIFEST.json]\n"
                            "Writes the manifest of an fba plugin (default: beside it, as <name>.manifest.json).\n";
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::cout << usage;
    return 0;
  }
  if (argc == 2 && std::string(argv[1]) == "--version") {
    std::cout << "fba-plugin-manifest " FBA_VERSION "\n";
    return 0;
  }
  if (argc < 2 || argc > 3) {
    std::cerr << usage;
    return 2;
  }
  const std::filesystem::path plugin = argv[1];
  const std::filesystem::path out = argc == 3 ? std::filesystem::path(argv[2]) : fba::detail::manifest_path(plugin);
  std::string text;
  try {
    text = fba::detail::manifest_json(fba::detail::describe_plugin(plugin));
  } catch (const std::exception& e) {
    std::cerr << "fba-plugin-manifest: " << plugin.string() << ": " << e.what() << "\n";
    return 1;
  }
  // Written whole to a temporary, then renamed: a half-written manifest never sits beside the plugin.
  const std::filesystem::path tmp = out.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    if (!f.flush()) {
      std::cerr << "fba-plugin-manifest: cannot write " << tmp.string() << "\n";
      return 1;
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, out, ec);
  if (ec) {
    std::cerr << "fba-plugin-manifest: cannot write " << out.string() << ": " << ec.message() << "\n";
    return 1;
  }
  return 0;
}
