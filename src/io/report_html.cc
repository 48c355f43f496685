#include "rotorguard/io/report_html.h"

#include <stdexcept>

#include <fmt/format.h>

namespace rotorguard::io {

namespace {

std::string EscapeHtml(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out.push_back(c);
    }
  }
  return out;
}

}  // namespace

std::string RenderReportHtml(std::string_view title, const nlohmann::json& data) {
  const std::string_view bundle = ViewerBundle();
  if (bundle.empty()) {
    throw std::runtime_error(
        "this rotorguard was built without the report viewer (npm was not found or "
        "ROTORGUARD_BUILD_VIEWER=OFF); install npm and rebuild to write reports");
  }
  // Inside a <script> element only "</" can end it early: JSON allows "\/" for "/", and the
  // bundler escapes it in the bundle's strings (checked, so a future bundle cannot break pages).
  std::string json = data.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  for (std::size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at + 3)) {
    json.replace(at, 2, "<\\/");
  }
  if (bundle.find("</script") != std::string_view::npos) {
    throw std::runtime_error("the viewer bundle contains '</script' and cannot be inlined; rebuild it");
  }
  std::string page;
  page.reserve(bundle.size() + json.size() + 1024);
  page += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  page += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  page += fmt::format("<title>{}</title>\n</head>\n<body>\n", EscapeHtml(title));
  page += "<div id=\"app\"></div>\n<script id=\"rotorguard-data\" type=\"application/json\">";
  page += json;
  page += "</script>\n<script>\n";
  page += bundle;
  page += "\n</script>\n</body>\n</html>\n";
  return page;
}

}  // namespace rotorguard::io
