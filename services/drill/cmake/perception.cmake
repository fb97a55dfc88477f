# concert_drill_perception (see ../CMakeLists.txt)
