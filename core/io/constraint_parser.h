// The `constraints:` section of run.yaml: linear pseudo-measurements on the
// parameters, e.g. {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}.
//
// expr is a sum of terms [coef[*]]name with + or - between them ("2*dpsi -
// 0.5 * dlambda2", "dx2"); names are the base parameters of docs/file-formats.md and
// effect parameters "effect.param". value_UNIT / sigma_UNIT take the suffix
// arcmin, arcsec, deg, rad (angle parameters only), mm, m (length parameters
// only), or none: then the value is in the file unit of the parameters, which
// must all share one unit. value defaults to 0; sigma is required and > 0.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "core/model/run_description.h"
#include "core/io/yaml_fields.h"

namespace triadcal {

// The paper's pseudo-measurement dpsi - dlambda2 = 0 +- 30 arcsec, used when a
// run.yaml has no `constraints` key.
std::vector<Constraint> DefaultConstraints();

// Parses the `constraints` list (`[]` gives none).
std::vector<Constraint> ParseConstraints(const YAML::Node& node, const YamlPlace& at);

// Parses "2*dpsi - dlambda2" into (name, coefficient) terms, merging repeated
// names; throws at.Fail(...) naming the unknown name or the bad token.
std::vector<std::pair<std::string, double>> ParseConstraintExpr(const std::string& expr,
                                                                const YamlPlace& at);

// The YAML map that ParseConstraints reads back to `c` (value_arcmin and
// sigma_arcsec for angles, mm for lengths, no suffix otherwise).
void EmitConstraint(const Constraint& c, YAML::Emitter* out);

}  // namespace triadcal
