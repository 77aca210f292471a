# Writes a C++ file defining scanmesh::sim::builtin_head_yaml() that returns the text of INPUT.
file(READ "${INPUT}" text)
# A raw string literal keeps the YAML byte for byte; the delimiter cannot occur in YAML here.
file(WRITE "${OUTPUT}" "#include <string>\nnamespace scanmesh::sim {\nconst std::string& builtin_head_yaml() {\n  static const std::string text = R\"scanmesh_yaml(${text})scanmesh_yaml\";\n  return text;\n}\n}  // namespace scanmesh::sim\n")
