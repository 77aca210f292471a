// The web UI's own files (apps/web/), compiled into the binary (cmake/embed_web_assets.cmake).
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

namespace scanmesh::cli::web {

struct WebAsset {
  std::string_view path;  //!< "/index.html"
  std::string_view content_type;
  const unsigned char* data;
  std::size_t size;
};

const std::vector<WebAsset>& web_assets();

}  // namespace scanmesh::cli::web
