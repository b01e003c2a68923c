#include "io/scene_validate.hpp"

#include <Teuchos_Array.hpp>
#include <sstream>
#include <stdexcept>

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
  return e.getAny().typeName();
}

// Promotes integers given where reals are expected (YAML reads "1" as int).
void promote(ParameterList& list, const std::string& key, const Teuchos::ParameterEntry& want) {
  const auto& have = list.getEntry(key);
  if (want.isType<double>() && have.isType<int>()) {
    list.set(key, static_cast<double>(list.get<int>(key)));
  } else if (want.isType<Array<double>>() && have.isType<Array<int>>()) {
    const auto ai = list.get<Array<int>>(key);
    list.set(key, Array<double>(ai.begin(), ai.end()));
  }
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
      msg << "scene key '" << where << "' = " << (have.isList() ? "{...}" : Teuchos::toString(have.getAny()))
          << ": wrong type " << type_name(have) << ", expected " << type_name(want);
      throw std::invalid_argument(msg.str());
    }
    if (!want.isList() && !want.validator().is_null()) {
      try {
        want.validator()->validate(have, key, path);
      } catch (const std::exception&) {
        std::ostringstream msg;
        msg << "scene key '" << where << "' = '" << Teuchos::toString(have.getAny())
            << "': not a valid value; expected " << want.docString();
        if (const auto valid = want.validator()->validStringValues(); !valid.is_null()) {
          msg << " (one of:";
          for (const auto& v : *valid) msg << " '" << v << "'";
          msg << ")";
        }
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
      if (!s->isParameter(part) || s->isSublist(part))
        throw std::invalid_argument("--set '" + path + "': unknown key '" + part + "'; expected one of " +
                                    valid_names(*s));
      const auto& want = s->getEntry(part);
      try {
        if (want.isType<double>()) l->set(part, std::stod(value));
        else if (want.isType<int>()) l->set(part, std::stoi(value));
        else if (want.isType<Array<double>>()) l->set(part, Teuchos::fromStringToArray<double>(value));
        else l->set(part, value);
      } catch (const std::exception&) {
        throw std::invalid_argument("--set '" + path + "' = '" + value + "': expected " + type_name(want));
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
