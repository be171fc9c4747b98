// The page's files (viewer/web/: index.html, viewer.js, viewer.css), embedded in the
// viewer at build time by viewer/embed_web.cmake: the viewer reads none of them from disk.
#pragma once

#include <optional>
#include <string_view>

namespace afhub::viewer {

// The bytes of the embedded file `name` ("viewer.js"), or nothing when there is none.
std::optional<std::string_view> web_file(std::string_view name);

}  // namespace afhub::viewer
