# GL entry points are loaded through glad, fed by the context's own getProcAddress
# (OSMesaGetProcAddress headless, glfwGetProcAddress in the window): never link -lGL
# (docs/RENDERING.md, "The GL loader story"). Generated at build time from Debian's python3-glad,
# offline (--reproducible uses the spec bundled with the package).
find_program(GLAD_EXECUTABLE glad REQUIRED)
set(GLAD_OUT ${CMAKE_BINARY_DIR}/glad)
add_custom_command(
  OUTPUT ${GLAD_OUT}/src/gl.c ${GLAD_OUT}/include/glad/gl.h
  COMMAND ${GLAD_EXECUTABLE} --api gl:core=3.3 --extensions GL_KHR_debug --reproducible --quiet
          --out-path ${GLAD_OUT} c
  COMMENT "Generating the GL 3.3 core loader with glad"
  VERBATIM)
add_library(glad STATIC ${GLAD_OUT}/src/gl.c)
target_include_directories(glad SYSTEM PUBLIC ${GLAD_OUT}/include)
set_target_properties(glad PROPERTIES POSITION_INDEPENDENT_CODE ON)
