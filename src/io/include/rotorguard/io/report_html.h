#pragma once
/// Self-contained HTML reports: the viewer bundle (built from viewer/ with npm) and the report's
/// data inlined in one page that opens offline, by double-click, with nothing beside it.
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace rotorguard::io {

/// The viewer's JavaScript bundle compiled into this program; empty when it was built without
/// npm (ROTORGUARD_BUILD_VIEWER=OFF).
std::string_view ViewerBundle();

/// Whether this program can write reports (it was built with the viewer).
inline bool HasViewer() { return !ViewerBundle().empty(); }

/// The page: `title` in its head, `data` as a JSON script element the viewer reads ("kind":
/// "flight" or "bench" selects the layout; docs/report.md). Throws std::runtime_error when the
/// program was built without the viewer.
std::string RenderReportHtml(std::string_view title, const nlohmann::json& data);

}  // namespace rotorguard::io
