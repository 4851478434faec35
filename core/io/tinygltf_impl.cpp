// tinygltf implementation unit: filled in with the glTF adapter.
