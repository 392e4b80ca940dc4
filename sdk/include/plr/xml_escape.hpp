// Text made safe for XML (SVG, HTML reports, DDS configuration).
#pragma once

#include <string>
#include <string_view>

namespace plr {

// `text` safe inside an XML element or a double-quoted attribute: & < > "
// as entities (PLR writes every attribute in double quotes). Link
// plr::sdk_support.
std::string xml_escape(std::string_view text);

}  // namespace plr
