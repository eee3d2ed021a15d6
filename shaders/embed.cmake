# Embeds GLSL sources into a C++ header at build time: OUT gets one raw string per file of
# SHADER_DIR (*.vert, *.frag).
file(GLOB SOURCES ${SHADER_DIR}/*.vert ${SHADER_DIR}/*.frag)
list(SORT SOURCES)
file(WRITE ${OUT} "// Generated from shaders/*.vert|frag by shaders/embed.cmake; do not edit.\n#pragma once\n")
foreach(src ${SOURCES})
  get_filename_component(name ${src} NAME)
  string(REPLACE "." "_" var ${name})
  file(READ ${src} text)
  file(APPEND ${OUT} "inline constexpr const char* kShader_${var} = R\"GLSL(${text})GLSL\";\n")
endforeach()
