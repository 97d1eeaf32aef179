#include "runner/verify/verify_walk_section.h"

#include <sstream>

#include "runner/verify/svg_plot.h"

namespace cellbake {

std::string walk_section_html(const VerifyWalkSection& walk, const std::string& worst_data_uri,
                              const std::string& plot_svg) {
  std::ostringstream h;
  h << "<h2 id=\"walk\">Walk</h2>\n";
  if (!walk.error.empty()) {
    h << "<p><b>The walk could not be rendered:</b> " << escape_xml(walk.error) << "</p>\n";
    return h.str();
  }
  h << "<p class=\"note\">A walk through the verified cells at walking speed (serpentine, eye height), each "
       "frame as ground truth | cells | error image; the plot shows PSNR and the cells frame time along it, "
       "dashed lines where the eye enters another cell.</p>\n";
  if (!walk.video.empty())
    h << "<video controls muted preload=\"metadata\" style=\"max-width:100%\" src=\"" << escape_xml(walk.video)
      << "\"></video>\n<p><a href=\"" << escape_xml(walk.video) << "\">" << escape_xml(walk.video)
      << "</a> (beside this report)</p>\n";
  else if (!walk.frames_dir.empty())
    h << "<p>Frames (PNG, no video encoder was found): <a href=\"" << escape_xml(walk.frames_dir) << "/\">"
      << escape_xml(walk.frames_dir) << "/</a></p>\n";
  if (!worst_data_uri.empty())
    h << "<div class=\"trip\"><h3>Worst frame of the walk</h3><img src=\"" << worst_data_uri
      << "\" alt=\"worst walk frame (" << escape_xml(walk.worst_png) << ")\"></div>\n";
  if (const auto at = plot_svg.find("<svg"); at != std::string::npos)
    h << "<div class=\"plots\"><!-- " << escape_xml(walk.plot) << " -->\n" << plot_svg.substr(at) << "</div>\n";
  if (!walk.summary_text.empty()) h << "<pre>" << escape_xml(walk.summary_text) << "</pre>\n";
  return h.str();
}

}  // namespace cellbake
