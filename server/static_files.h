// The browser client's files, served at GET /: a request path resolved inside the web root only
// (no "..", no absolute paths, no symlinks leading out), with its content type. When the web root
// has no index.html, "/" gets a built-in page that says how to reach the server.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace isomesh::server {

struct StaticFile {
    std::string body;
    std::string content_type;
};

enum class FileLookup { found, not_found, forbidden };

struct FileResult {
    FileLookup status = FileLookup::not_found;
    StaticFile file;
};

/// The file for the URL path `target` (query string ignored, percent-escapes decoded) under
/// `web_root`; "/" and folders mean their index.html. Forbidden: escapes, NUL bytes, dot files.
FileResult load_static_file(const std::string& web_root, std::string_view target);

/// The MIME type for a file name, by extension ("application/octet-stream" when unknown).
std::string_view content_type_for(std::string_view path);

/// The page served at "/" when the web root has no index.html.
const std::string& builtin_index_page();

}  // namespace isomesh::server
