// The live views (fba/view.hpp) of the image types (Frame, Silhouette), registered when their
// library, libfba_types, loads.
//
// frame.hpp (and so silhouette.hpp) includes this one, so that whatever uses an image type loads
// the library that shows it: the reference below keeps the library among a plugin's needed
// libraries, which the linker's --as-needed (Debian's default) would otherwise drop when the
// plugin calls nothing of it.
#pragma once

namespace fba::types_detail {
[[gnu::visibility("default")]] extern const bool image_views_registered;
[[gnu::used]] inline const bool* const keep_image_views = &image_views_registered;
}  // namespace fba::types_detail
