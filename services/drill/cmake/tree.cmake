# concert_drill_tree (see ../CMakeLists.txt)
