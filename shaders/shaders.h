// GLSL sources embedded into the binary at build time (see CMakeLists.txt). Shaders are named by
// their file name in shaders/ ("mesh_depth.frag"); the extension gives the stage (.vert, .geom,
// .frag, .comp); *.glsl files are pieces for `#include "name.glsl"`.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ms::shaders {

// The file's text as written. Throws InternalError for an unknown name (a programming error:
// the names are fixed at build time), listing the known ones.
std::string_view Source(std::string_view name);

bool Has(std::string_view name);
std::vector<std::string_view> Names();  // sorted

// Source(name) with every line `#include "other.glsl"` replaced by that embedded file (nested
// includes allowed; a file included twice is inserted once). `#line` directives keep compiler
// line numbers right: GLSL numbers source strings, so lines of the i-th included file (in order
// of first inclusion, 1-based) report as "i:<line>"; the main file is 0. included_names receives
// the names in that order (index 0 = `name`) so messages can name the file.
std::string Expand(std::string_view name, std::vector<std::string>* included_names = nullptr);

}  // namespace ms::shaders
