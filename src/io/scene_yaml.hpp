#pragma once
// Scene YAML text to a Teuchos::ParameterList without a raw library message:
// a pre-scan refuses a key that appears twice in one mapping (block mappings
// by indentation, flow mappings {a: 1, b: 2}) naming its path and both lines;
// every exception of the Teuchos parser becomes std::invalid_argument naming
// the scene and, when the parser reports it, the line. Also parses one
// `--set` value with the parser the file goes through, so both get the same
// types.
#include <Teuchos_ParameterList.hpp>
#include <string>

namespace bfemp {

// Throws std::invalid_argument "<label> line 42: key 'Contact/kappa' appears
// twice (first at line 40)". Paths leave out the top-level key 'bfemp', as
// every other scene message does. `label` is e.g. "scene file 'a.yaml'".
void check_duplicate_keys(const std::string& yaml, const std::string& label);

// check_duplicate_keys, then Teuchos::getParametersFromYamlString; any
// parser exception is rethrown as std::invalid_argument naming `label`.
Teuchos::RCP<Teuchos::ParameterList> parse_scene_yaml(const std::string& yaml, const std::string& label);

// The entry the scene file would hold for `key: <value>`: a YAML scalar
// (true/false, 1, 1.5, 1e-3, text) or flow sequence ([1.0, 0.0]); the older
// form {1.0, 0.0} (a brace list without ':') is read as a sequence.
// Throws std::invalid_argument naming `what` when the value is not YAML.
Teuchos::ParameterEntry parse_yaml_value(const std::string& value, const std::string& what);

}  // namespace bfemp
