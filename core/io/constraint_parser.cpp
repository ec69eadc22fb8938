// Parsing and writing of the `constraints:` section of run.yaml (see the header).
#include "core/io/constraint_parser.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>

#include "core/io/file_util.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

// Every parameter a constraint may name: base parameters and all effects'.
const ParameterLayout& AllParameters() {
  static const ParameterLayout layout = [] {
    std::vector<Effect> all;
    for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
    return ParameterLayout(all);
  }();
  return layout;
}

enum class UnitKind { kAngle, kLength, kOther };

UnitKind KindOfUnit(const std::string& unit) {
  if (unit == "arcmin" || unit == "arcsec" || unit == "deg" || unit == "rad") {
    return UnitKind::kAngle;
  }
  if (unit == "mm" || unit == "m") return UnitKind::kLength;
  return UnitKind::kOther;
}

double SiPerSuffix(const std::string& suffix) {
  if (suffix == "arcmin") return kArcminToRad;
  if (suffix == "arcsec") return kArcsecToRad;
  if (suffix == "deg") return kDegToRad;
  if (suffix == "mm") return kMmToM;
  return 1.0;  // rad, m
}

const std::vector<std::string>& Suffixes() {
  static const std::vector<std::string> s = {"arcmin", "arcsec", "deg", "rad", "mm", "m"};
  return s;
}

bool IsNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

std::string BaseNameList() {
  std::string list;
  for (const ParameterInfo& p : BaseParameterInfo()) list += (list.empty() ? "" : " ") + p.name;
  return list;
}

// A value_/sigma_ key of one constraint: the number and its suffix ("" = none).
struct SuffixedValue {
  double value = 0.0;
  std::string suffix;
  std::string key;
};

std::optional<SuffixedValue> FindSuffixed(const YAML::Node& node, const YamlPlace& at,
                                          const std::string& stem) {
  std::optional<SuffixedValue> found;
  for (const auto& kv : node) {
    const std::string key = KeyOf(kv.first, at);
    std::string suffix;
    if (key == stem) {
      suffix = "";
    } else if (key.rfind(stem + "_", 0) == 0) {
      suffix = key.substr(stem.size() + 1);
    } else {
      continue;
    }
    if (found) at.Fail("both '" + found->key + "' and '" + key + "' given; use one");
    found = SuffixedValue{ReadNumber(kv.second, at.Child(key)), suffix, key};
  }
  return found;
}

// SI value of v for the parameters of the terms (see the header for the rules).
double ToSi(const SuffixedValue& v, const std::vector<std::pair<std::string, double>>& terms,
            const YamlPlace& at) {
  const ParameterLayout& all = AllParameters();
  if (v.suffix.empty()) {
    const ParameterInfo& first = all.info(all.IndexOf(terms.front().first));
    for (const auto& [name, coef] : terms) {
      const ParameterInfo& p = all.info(all.IndexOf(name));
      if (p.unit != first.unit) {
        at.Child(v.key).Fail("parameters of different units (" + first.name + " in " + first.unit +
                             ", " + p.name + " in " + p.unit +
                             "); give the unit as a suffix, e.g. " + v.key + "_arcmin");
      }
    }
    return v.value * first.si_per_unit;
  }
  const UnitKind kind = KindOfUnit(v.suffix);
  if (kind == UnitKind::kOther) {
    at.Child(v.key).Fail("unknown unit suffix '" + v.suffix +
                         "' (allowed: arcmin, arcsec, deg, rad, mm, m, or none)");
  }
  for (const auto& [name, coef] : terms) {
    const ParameterInfo& p = all.info(all.IndexOf(name));
    if (KindOfUnit(p.unit) != kind) {
      at.Child(v.key).Fail(std::string(kind == UnitKind::kAngle ? "an angle" : "a length") +
                           " unit, but " + p.name + " is in " + p.unit);
    }
  }
  return v.value * SiPerSuffix(v.suffix);
}

Constraint ParseOneConstraint(const YAML::Node& node, const YamlPlace& at) {
  if (!node.IsMap()) {
    at.Fail("expected a map {expr: ..., value_arcmin: ..., sigma_arcsec: ...}, got " +
            DescribeNode(node));
  }
  std::vector<std::string> allowed = {"expr", "value", "sigma"};
  for (const std::string& s : Suffixes()) {
    allowed.push_back("value_" + s);
    allowed.push_back("sigma_" + s);
  }
  CheckKeys(node, at, allowed);
  if (!node["expr"]) at.Fail("missing 'expr' (e.g. expr: \"dpsi - dlambda2\")");
  Constraint c;
  c.expr = ReadString(node["expr"], at.Child("expr"));
  c.terms = ParseConstraintExpr(c.expr, at.Child("expr"));
  const std::optional<SuffixedValue> value = FindSuffixed(node, at, "value");
  const std::optional<SuffixedValue> sigma = FindSuffixed(node, at, "sigma");
  if (!sigma) at.Fail("missing sigma (e.g. sigma_arcsec: 30)");
  c.value_si = value ? ToSi(*value, c.terms, at) : 0.0;
  if (!(sigma->value > 0.0)) {
    at.Child(sigma->key).Fail("must be > 0, got " + FormatDouble(sigma->value));
  }
  c.sigma_si = ToSi(*sigma, c.terms, at);
  return c;
}

}  // namespace

std::vector<Constraint> DefaultConstraints() {
  Constraint c;
  c.expr = "dpsi - dlambda2";
  c.terms = {{"dpsi", 1.0}, {"dlambda2", -1.0}};
  c.value_si = 0.0;
  c.sigma_si = 30.0 * kArcsecToRad;
  return {c};
}

std::vector<Constraint> ParseConstraints(const YAML::Node& node, const YamlPlace& at) {
  if (node.IsNull()) return {};
  if (!node.IsSequence()) at.Fail("expected a list of constraints, got " + DescribeNode(node));
  std::vector<Constraint> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    out.push_back(ParseOneConstraint(node[i], at.Index(i)));
  }
  return out;
}

std::vector<std::pair<std::string, double>> ParseConstraintExpr(const std::string& expr,
                                                                const YamlPlace& at) {
  const ParameterLayout& all = AllParameters();
  std::vector<std::pair<std::string, double>> terms;
  const std::size_t n = expr.size();
  std::size_t i = 0;
  auto skip_space = [&] {
    while (i < n && std::isspace(static_cast<unsigned char>(expr[i]))) ++i;
  };
  auto fail_at = [&](const std::string& what) {
    at.Fail(what + " at position " + std::to_string(i + 1) + " of \"" + expr + "\"");
  };
  skip_space();
  if (i == n) at.Fail("empty expression");
  bool first = true;
  while (true) {
    skip_space();
    double sign = 1.0;
    if (i < n && (expr[i] == '+' || expr[i] == '-')) {
      sign = expr[i] == '-' ? -1.0 : 1.0;
      ++i;
      skip_space();
    } else if (!first) {
      fail_at("expected '+' or '-'");
    }
    first = false;
    double coef = 1.0;
    if (i < n && (std::isdigit(static_cast<unsigned char>(expr[i])) || expr[i] == '.')) {
      const auto res = std::from_chars(expr.data() + i, expr.data() + n, coef);
      if (res.ec != std::errc()) fail_at("bad number");
      const std::size_t number_start = i;
      i = static_cast<std::size_t>(res.ptr - expr.data());
      skip_space();
      if (i < n && expr[i] == '*') {
        ++i;
        skip_space();
      }
      if (i == n || !IsNameStart(expr[i])) {
        at.Fail("constant term '" + expr.substr(number_start, i - number_start) + "' in \"" + expr +
                "\" (put constants in value_...)");
      }
    }
    if (i == n || !IsNameStart(expr[i])) fail_at("expected a parameter name");
    const std::size_t start = i;
    while (i < n && IsNameChar(expr[i])) ++i;
    if (i + 1 < n && expr[i] == '.' && IsNameStart(expr[i + 1])) {
      ++i;
      while (i < n && IsNameChar(expr[i])) ++i;
    }
    const std::string name = expr.substr(start, i - start);
    if (all.IndexOf(name) < 0) {
      at.Fail("unknown parameter '" + name + "' in \"" + expr + "\" (known: " + BaseNameList() +
              ", and effect.param names, see `triadcal params`)");
    }
    bool merged = false;
    for (auto& t : terms) {
      if (t.first == name) {
        t.second += sign * coef;
        merged = true;
      }
    }
    if (!merged) terms.emplace_back(name, sign * coef);
    skip_space();
    if (i == n) break;
  }
  bool any = false;
  for (const auto& t : terms) any = any || t.second != 0.0;
  if (!any) at.Fail("all coefficients are zero in \"" + expr + "\"");
  return terms;
}

void EmitConstraint(const Constraint& c, YAML::Emitter* out) {
  const ParameterLayout& all = AllParameters();
  std::string value_key = "value", sigma_key = "sigma";
  double value_per_si = 1.0, sigma_per_si = 1.0;
  UnitKind kind = UnitKind::kOther;
  bool same_kind = true;
  for (std::size_t j = 0; j < c.terms.size(); ++j) {
    const int idx = all.IndexOf(c.terms[j].first);
    const UnitKind k = idx < 0 ? UnitKind::kOther : KindOfUnit(all.info(idx).unit);
    if (j == 0) kind = k;
    same_kind = same_kind && k == kind;
  }
  if (same_kind && kind == UnitKind::kAngle) {
    value_key = "value_arcmin";
    sigma_key = "sigma_arcsec";
    value_per_si = 1.0 / kArcminToRad;
    sigma_per_si = 1.0 / kArcsecToRad;
  } else if (same_kind && kind == UnitKind::kLength) {
    value_key = "value_mm";
    sigma_key = "sigma_mm";
    value_per_si = sigma_per_si = 1.0 / kMmToM;
  } else if (!c.terms.empty() && all.IndexOf(c.terms[0].first) >= 0) {
    value_per_si = sigma_per_si = 1.0 / all.info(all.IndexOf(c.terms[0].first)).si_per_unit;
  }
  *out << YAML::Flow << YAML::BeginMap;
  std::string expr = c.expr;
  if (expr.empty()) {  // a constraint built in code may carry terms only
    for (const auto& [name, coef] : c.terms) {
      const std::string sign = coef < 0 ? " - " : " + ";
      const std::string mag = std::abs(coef) == 1.0 ? "" : FormatDouble(std::abs(coef)) + "*";
      expr += (expr.empty() ? (coef < 0 ? "-" : "") : sign) + mag + name;
    }
  }
  *out << YAML::Key << "expr" << YAML::Value << YAML::DoubleQuoted << expr;
  *out << YAML::Key << value_key << YAML::Value << FormatDouble(c.value_si * value_per_si);
  *out << YAML::Key << sigma_key << YAML::Value << FormatDouble(c.sigma_si * sigma_per_si);
  *out << YAML::EndMap;
}

}  // namespace triadcal
