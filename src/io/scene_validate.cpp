#include "io/scene_validate.hpp"

#include <Teuchos_Array.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "io/scene_yaml.hpp"

namespace bfemp {

using Teuchos::Array;
using Teuchos::ParameterList;

namespace {

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "/" + key;
}

std::string valid_names(const ParameterList& schema) {
  std::string s;
  for (auto it = schema.begin(); it != schema.end(); ++it) s += (s.empty() ? "'" : ", '") + schema.name(it) + "'";
  return s.empty() ? "(none)" : s;
}

std::string type_name(const Teuchos::ParameterEntry& e) {
  if (e.isList()) return "sublist";
  if (e.isType<double>()) return "real number";
  if (e.isType<int>()) return "integer";
  if (e.isType<std::string>()) return "string";
  if (e.isType<bool>()) return "boolean";
  if (e.isType<Array<double>>()) return "list of real numbers";
  if (e.isType<Array<int>>()) return "list of integers";
  if (e.isType<Array<std::string>>()) return "list of strings";
  return e.getAny().typeName();
}

// Promotes integers given where reals are expected (YAML reads "1" as int),
// 0 and 1 where a boolean is expected, and whole reals (2.0, 1e3) within
// range where an integer is expected (also in lists, and the untyped []).
void promote(ParameterList& list, const std::string& key, const Teuchos::ParameterEntry& want) {
  const auto& have = list.getEntry(key);
  if (want.isType<double>() && have.isType<int>()) {
    list.set(key, static_cast<double>(list.get<int>(key)));
  } else if (want.isType<Array<double>>() && have.isType<Array<int>>()) {
    const auto ai = list.get<Array<int>>(key);
    list.set(key, Array<double>(ai.begin(), ai.end()));
  } else if (want.isType<Array<int>>() && have.isType<Array<double>>()) {
    // "[]" (typed as reals: the parser cannot type it) and whole reals: integers
    const auto ad = list.get<Array<double>>(key);
    Array<int> ai;
    for (const double v : ad) {
      if (!(v == std::floor(v) && std::abs(v) <= 2147483647.0)) return;
      ai.push_back(static_cast<int>(v));
    }
    list.set(key, ai);
  } else if (want.isType<bool>() && have.isType<int>() && (list.get<int>(key) == 0 || list.get<int>(key) == 1)) {
    list.set(key, list.get<int>(key) == 1);
  } else if (want.isType<int>() && have.isType<double>()) {
    const double v = list.get<double>(key);
    if (v == std::floor(v) && std::abs(v) <= 2147483647.0) list.set(key, static_cast<int>(v));
  }
}

// What a mistyped value is, for the message: a number out of range or NaN
// written as text, a key without a value, or its type.
// True for text that names a number no double holds: 1e400, nan, .inf, -.Inf
// (the YAML parser leaves them strings).
bool non_finite_number(const std::string& t) {
  std::string l;
  for (char c : t) l += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!l.empty() && (l[0] == '+' || l[0] == '-')) l = l.substr(1);
  if (l == ".nan" || l == ".inf" || l == "nan" || l == "inf" || l == "infinity") return true;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  return !t.empty() && end == t.c_str() + t.size() && !std::isfinite(v);
}

std::string what_it_is(const Teuchos::ParameterEntry& have, const Teuchos::ParameterEntry& want) {
  if (have.isList()) return have.getValue<ParameterList>(nullptr).numParams() == 0 ? "no value" : "a map";
  if (have.isType<std::string>() && (want.isType<double>() || want.isType<int>())) {
    const std::string t = Teuchos::getValue<std::string>(have);
    if (non_finite_number(t)) return "not a finite number";
    if (t.empty()) return "an empty string";
  }
  if (have.isType<Array<std::string>>() && want.isType<Array<double>>())
    for (const auto& t : Teuchos::getValue<Array<std::string>>(have))
      if (non_finite_number(t)) return "a component '" + t + "' is not a finite number";
  return "wrong type " + type_name(have);
}

template <class T>
std::string shown_array(const Array<T>& a) {
  std::ostringstream s;
  s << "[";
  for (typename Array<T>::size_type i = 0; i < a.size(); ++i) s << (i ? ", " : "") << a[i];
  s << "]";
  return s.str();
}

std::string shown(const Teuchos::ParameterEntry& e) {
  if (e.isList()) return e.getValue<ParameterList>(nullptr).numParams() == 0 ? "(nothing)" : "{...}";
  if (e.isType<std::string>()) return "'" + Teuchos::getValue<std::string>(e) + "'";
  if (e.isType<Array<double>>()) return shown_array(Teuchos::getValue<Array<double>>(e));
  if (e.isType<Array<int>>()) return shown_array(Teuchos::getValue<Array<int>>(e));
  if (e.isType<Array<std::string>>()) return shown_array(Teuchos::getValue<Array<std::string>>(e));
  return Teuchos::toString(e.getAny());
}

// Non-finite reals (possible through --set and programmatic lists) are refused.
void require_finite(const Teuchos::ParameterEntry& e, const std::string& where) {
  bool ok = true;
  if (e.isType<double>()) ok = std::isfinite(Teuchos::getValue<double>(e));
  if (e.isType<Array<double>>())
    for (double v : Teuchos::getValue<Array<double>>(e)) ok = ok && std::isfinite(v);
  if (!ok) throw std::invalid_argument("scene key '" + where + "' = " + shown(e) + ": expected finite numbers");
}

}  // namespace

void validate_scene_list(ParameterList& list, const ParameterList& schema, const std::string& path) {
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string& key = list.name(it);
    const std::string where = join(path, key);
    if (!schema.isParameter(key)) {
      throw std::invalid_argument("scene key '" + where + "': unknown key; expected one of " +
                                  valid_names(schema));
    }
    const auto& want = schema.getEntry(key);
    promote(list, key, want);
    const auto& have = list.getEntry(key);
    if (have.isList() != want.isList() || (!want.isList() && have.getAny().type() != want.getAny().type())) {
      std::ostringstream msg;
      msg << "scene key '" << where << "' = " << shown(have) << ": " << what_it_is(have, want) << ", expected "
          << type_name(want);
      if (want.isType<bool>()) msg << " (true or false)";
      throw std::invalid_argument(msg.str());
    }
    require_finite(have, where);
    if (!want.isList() && !want.validator().is_null()) {
      try {
        want.validator()->validate(have, key, path);
      } catch (const std::exception&) {
        std::ostringstream msg;
        msg << "scene key '" << where << "' = " << shown(have) << ": expected ";
        const auto& v = *want.validator();
        if (const auto valid = v.validStringValues(); !valid.is_null()) {
          msg << "one of";
          for (decltype(valid->size()) i = 0; i < valid->size(); ++i) msg << (i ? ", '" : " '") << (*valid)[i] << "'";
        } else if (const auto* d = dynamic_cast<const Teuchos::EnhancedNumberValidator<double>*>(&v)) {
          msg << "a value in [" << d->getMin() << ", " << d->getMax() << "]";
        } else if (const auto* n = dynamic_cast<const Teuchos::EnhancedNumberValidator<int>*>(&v)) {
          msg << "an integer in [" << n->getMin() << ", " << n->getMax() << "]";
        } else {
          msg << "a valid value";
        }
        if (!want.docString().empty()) msg << " (" << want.docString() << ")";
        throw std::invalid_argument(msg.str());
      }
    }
  }
  // Defaults and recursion.
  for (auto it = schema.begin(); it != schema.end(); ++it) {
    const std::string& key = schema.name(it);
    const auto& want = schema.entry(it);
    if (!want.isList()) {
      if (!list.isParameter(key)) list.setEntry(key, want);
      continue;
    }
    ParameterList& sub = list.sublist(key);
    if (scene_is_container(key)) {
      const ParameterList& child = scene_child_schema(key);
      for (auto c = sub.begin(); c != sub.end(); ++c) {
        const std::string cname = sub.name(c);
        if (!sub.entry(c).isList())
          throw std::invalid_argument("scene key '" + join(join(path, key), cname) +
                                      "': expected a sublist (a named " + child.name() + ")");
        validate_scene_list(sub.sublist(cname), child, join(join(path, key), cname));
      }
    } else if (schema.sublist(key).numParams() > 0) {  // empty schema: free-form (Ifpack2)
      validate_scene_list(sub, schema.sublist(key), join(path, key));
    }
  }
}

void apply_scene_override(ParameterList& list, const ParameterList& schema, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument("--set '" + assignment + "': expected path/to/key=value");
  const std::string path = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  ParameterList* l = &list;
  const ParameterList* s = &schema;
  std::size_t start = 0;
  std::string parent;
  while (true) {
    const auto slash = path.find('/', start);
    const std::string part = path.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (slash == std::string::npos) {
      const std::string what = "--set '" + path + "'";
      if (s->numParams() == 0 && !scene_is_container(parent)) {  // free-form: Ifpack2, Friction Pairs
        l->setEntry(part, parse_yaml_value(value, what));
        return;
      }
      if (s->isSublist(part))
        throw std::invalid_argument(what + ": '" + part + "' is a sublist; set one of its keys, '" + path +
                                    "/<key>=value'");
      if (!s->isParameter(part))
        throw std::invalid_argument(what + ": unknown key '" + part + "'; expected one of " + valid_names(*s));
      const auto& want = s->getEntry(part);
      if (want.isType<std::string>()) {  // text as written; quotes optional
        std::string t = value;
        if (t.size() >= 2 && (t.front() == '\'' || t.front() == '"') && t.back() == t.front())
          t = t.substr(1, t.size() - 2);
        l->set(part, t);
        return;
      }
      try {
        l->setEntry(part, parse_yaml_value(value, what));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string(e.what()) + "; expected " + type_name(want));
      }
      promote(*l, part, want);
      const auto& have = l->getEntry(part);
      if (have.isList() || have.getAny().type() != want.getAny().type()) {
        std::string expected = type_name(want);
        if (want.isType<bool>()) expected += " (true, false, True, False, yes, no, 1 or 0)";
        if (want.isType<Array<double>>()) expected += " written [x, y] (or {x, y})";
        if (want.isType<int>()) expected += " (a whole number)";
        throw std::invalid_argument(what + " = '" + value + "': " + what_it_is(have, want) + ", expected " +
                                    expected);
      }
      try {
        require_finite(have, path);
      } catch (const std::invalid_argument&) {
        throw std::invalid_argument(what + " = '" + value + "': expected finite numbers");
      }
      return;
    }
    if (scene_is_container(parent) ) {
      if (!l->isSublist(part))
        throw std::invalid_argument("--set '" + path + "': no entry '" + part + "' in '" + parent + "'");
      s = &scene_child_schema(parent);
    } else {
      if (!s->isSublist(part))
        throw std::invalid_argument("--set '" + path + "': unknown sublist '" + part + "'; expected one of " +
                                    valid_names(*s));
      s = &s->sublist(part);
    }
    if (scene_is_container(part)) {
      l = &l->sublist(part);
      parent = part;
    } else {
      l = &l->sublist(part);
      parent = "";
    }
    start = slash + 1;
  }
}

}  // namespace bfemp
