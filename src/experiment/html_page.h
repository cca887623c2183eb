// The comparison report's index.html: an image viewer (switch integrators by key or click,
// zoom with the wheel and pan by dragging — the view is shared by every image, so switching
// keeps the same region; reference and false-colour error views), the convergence plot and
// the summary table. Everything is inline: the page works from disk with no network.
// Opening it with the fragment #selftest exercises the viewer and reports the outcome in the
// page title ("selftest:pass" or "selftest:fail: reason") for the headless browser test.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiment/comparison.h"

namespace caustica {

std::string comparison_html(const ComparisonResult& result, const nlohmann::json& summary,
                            const std::string& svg);

}  // namespace caustica
