// The report's HTML: the static parts written here, the plots and the 3D view drawn by the
// page's script from the JSON data block. Internal to protocols/report.
#pragma once

#include <string>

namespace selfcal::report {

struct PageParts {
  std::string title;
  std::string body_html;  // the sections written in C++ (decision, summary, rollback)
  std::string data_json;  // the data block
  std::string libraries;  // three.js, OrbitControls, Chart.js, concatenated
  std::string licences_html;
};

std::string RenderPage(const PageParts& parts);

}  // namespace selfcal::report
