#include "server/static_files.h"

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

namespace isomesh::server {
namespace {

namespace fs = std::filesystem;

int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/// Decodes %XX escapes; nothing for a malformed escape.
std::optional<std::string> percent_decode(std::string_view text) {
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] != '%') {
            out += text[i];
            continue;
        }
        if (i + 2 >= text.size()) return std::nullopt;
        const int high = hex_value(text[i + 1]), low = hex_value(text[i + 2]);
        if (high < 0 || low < 0) return std::nullopt;
        out += static_cast<char>(high * 16 + low);
        i += 2;
    }
    return out;
}

/// The relative path of a URL path, or nothing when a segment is empty-named trickery: "..",
/// ".", a dot file, a backslash or a NUL byte.
std::optional<fs::path> safe_relative_path(std::string_view decoded) {
    fs::path relative;
    std::size_t start = 0;
    while (start <= decoded.size()) {
        std::size_t end = decoded.find('/', start);
        if (end == std::string_view::npos) end = decoded.size();
        const std::string_view segment = decoded.substr(start, end - start);
        if (!segment.empty()) {
            if (segment.front() == '.' || segment.find('\\') != std::string_view::npos ||
                segment.find('\0') != std::string_view::npos)
                return std::nullopt;
            relative /= std::string(segment);
        }
        start = end + 1;
    }
    return relative;
}

std::optional<std::string> read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream out;
    out << in.rdbuf();
    return std::move(out).str();
}

}  // namespace

std::string_view content_type_for(std::string_view path) {
    static constexpr std::array<std::pair<std::string_view, std::string_view>, 14> kTypes = {{
        {".html", "text/html; charset=utf-8"},
        {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".json", "application/json"},
        {".wasm", "application/wasm"},
        {".svg", "image/svg+xml"},
        {".png", "image/png"},
        {".jpg", "image/jpeg"},
        {".ico", "image/x-icon"},
        {".txt", "text/plain; charset=utf-8"},
        {".md", "text/markdown; charset=utf-8"},
        {".vm", "text/plain; charset=utf-8"},
        {".map", "application/json"},
    }};
    for (const auto& [extension, type] : kTypes) {
        if (path.ends_with(extension)) return type;
    }
    return "application/octet-stream";
}

FileResult load_static_file(const std::string& web_root, std::string_view target) {
    target = target.substr(0, target.find_first_of("?#"));
    const auto decoded = percent_decode(target);
    if (!decoded || decoded->empty() || decoded->front() != '/') return {FileLookup::forbidden, {}};
    const auto relative = safe_relative_path(*decoded);
    if (!relative) return {FileLookup::forbidden, {}};

    // "/index.html/" names a folder: only a folder may be served under a path ending in '/'.
    const bool folder_path = decoded->back() == '/';
    const bool root_index = relative->empty() || (*relative == "index.html" && !folder_path);
    const FileResult builtin{FileLookup::found, {builtin_index_page(), "text/html; charset=utf-8"}};
    if (web_root.empty()) return root_index ? builtin : FileResult{};
    std::error_code error;
    fs::path path = fs::path(web_root) / *relative;
    if (fs::is_directory(path, error)) {
        path /= "index.html";
    } else if (folder_path) {
        return FileResult{};
    }
    if (!fs::is_regular_file(path, error)) return root_index ? builtin : FileResult{};
    // Symbolic links may point anywhere: serve only what resolves inside the root.
    const fs::path root = fs::weakly_canonical(web_root, error);
    const fs::path resolved = fs::weakly_canonical(path, error);
    if (error) return {FileLookup::not_found, {}};
    const auto [root_end, unused] =
        std::mismatch(root.begin(), root.end(), resolved.begin(), resolved.end());
    if (root_end != root.end()) return {FileLookup::forbidden, {}};
    auto body = read_file(resolved);
    if (!body) return {FileLookup::not_found, {}};
    return {FileLookup::found, {std::move(*body), std::string(content_type_for(path.string()))}};
}

const std::string& builtin_index_page() {
    static const std::string page = R"(<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>isomesh server</title>
<style>
body { font: 16px/1.5 system-ui, sans-serif; max-width: 44em; margin: 3em auto; padding: 0 1em; }
code { background: #f3f3f3; padding: 0 .25em; }
</style>
</head>
<body>
<h1>isomesh server</h1>
<p>This server turns implicit equations such as <code>x^2+y^2+z^2+2cos(2x)=5</code> into
triangle meshes and streams them over WebSocket.</p>
<p>The browser client is not installed here (start the server with
<code>--web-root DIR</code> pointing at <code>clients/web</code>). Meanwhile:</p>
<ul>
<li>WebSocket endpoint: <code>/ws</code> (the protocol is described in
<code>protocol/PROTOCOL.md</code>)</li>
<li>Health: <a href="/healthz">/healthz</a></li>
<li>Metrics (Prometheus): <a href="/metrics">/metrics</a></li>
</ul>
<p id="status">Checking the WebSocket endpoint…</p>
<script>
const status = document.getElementById("status");
const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
ws.onopen = () => ws.send(JSON.stringify({v: 1, type: "ping", id: 1}));
ws.onmessage = (event) => { status.textContent = "WebSocket answered: " + event.data; ws.close(); };
ws.onerror = () => { status.textContent = "WebSocket connection failed."; };
</script>
</body>
</html>
)";
    return page;
}

}  // namespace isomesh::server
