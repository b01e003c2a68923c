#pragma once
// Validation of a scene ParameterList against its schema, with messages that
// name the key path, the value and what was expected.
#include <Teuchos_ParameterList.hpp>
#include <string>

namespace bfemp {

// Schema of each child of a named container ("Materials", "FEM Bodies", ...).
const Teuchos::ParameterList& scene_child_schema(const std::string& container);
bool scene_is_container(const std::string& name);

// Checks names and types level by level (int -> double and int arrays ->
// double arrays are promoted), fills defaults, runs the value validators.
void validate_scene_list(Teuchos::ParameterList& list, const Teuchos::ParameterList& schema,
                         const std::string& path);

// Applies "a/b/key=value" to `list`, typed after the schema entry.
void apply_scene_override(Teuchos::ParameterList& list, const Teuchos::ParameterList& schema,
                          const std::string& assignment);

}  // namespace bfemp
