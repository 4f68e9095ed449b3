//! Reading and writing meshes: OFF, OBJ, PLY, STL. Errors name file, line and problem.
