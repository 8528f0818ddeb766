#pragma once
// The style sheet and the script of the HTML report (our own code: no library, no network), kept in
// assets/report.css and assets/report.js and embedded at build time (cmake/SemslamEmbedText.cmake). The script reads
// <script type="application/json" id="semslam-data"> when the page has one, draws the 3D view (WebGL, or a 2D
// canvas when WebGL is missing or the page address ends in #canvas2d), and makes tables with class "sortable"
// sortable by a click on a column header. It sets data-viewer ("webgl", "canvas2d" or "none") on <body> and
// lists JavaScript errors in #js-errors.

#include <string_view>

namespace semslam {

std::string_view HtmlReportCss();
std::string_view HtmlReportScript();

}  // namespace semslam
