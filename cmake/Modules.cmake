# The library's modules and the layers they form (docs/architecture.md, "Layers"). Each module
# is a static library tendril_<module> linking exactly the modules below it that it uses; its
# headers are reachable only through an include directory of its own
# (build/modules/<module>/tendril/<module> links to src/tendril/<module>), which a target sees
# only by linking the module. So `#include "tendril/session/session.h"` in env/ fails to build:
# the header is not on env's include path. tests/layers checks that it does.

# Third-party packages by what uses them (cmake/Dependencies.cmake finds them).
add_library(tendril_deps_base INTERFACE)
target_link_libraries(tendril_deps_base INTERFACE
  Eigen3::Eigen TBB::tbb nlohmann_json::nlohmann_json spdlog::spdlog fmt::fmt Threads::Threads)

set(TENDRIL_MODULE_INCLUDE_ROOT ${PROJECT_BINARY_DIR}/modules)
set(TENDRIL_MODULES "")

# tendril_module(NAME DEPS <modules...> [PRIVATE_DEPS <modules...>] [PACKAGES <third-party targets...>])
# PRIVATE_DEPS are modules the module's sources use but its headers do not show: they are
# linked, and their headers stay hidden from the module's own users.
function(tendril_module name)
  cmake_parse_arguments(M "" "" "DEPS;PRIVATE_DEPS;PACKAGES" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/tendril/${name}/*.cpp)
  add_library(tendril_${name} STATIC ${sources})
  set(include_dir ${TENDRIL_MODULE_INCLUDE_ROOT}/${name})
  file(MAKE_DIRECTORY ${include_dir}/tendril)
  if(NOT EXISTS ${include_dir}/tendril/${name})
    file(CREATE_LINK ${PROJECT_SOURCE_DIR}/src/tendril/${name} ${include_dir}/tendril/${name} SYMBOLIC)
  endif()
  target_include_directories(tendril_${name} PUBLIC ${include_dir})
  set(deps tendril_deps_base)
  foreach(d IN LISTS M_DEPS)
    list(APPEND deps tendril_${d})
  endforeach()
  target_link_libraries(tendril_${name} PUBLIC ${deps} ${M_PACKAGES})
  foreach(d IN LISTS M_PRIVATE_DEPS)
    target_link_libraries(tendril_${name} PRIVATE tendril_${d})
  endforeach()
  target_compile_options(tendril_${name} PRIVATE -Wall -Wextra -Wno-unused-parameter)
  target_compile_definitions(tendril_${name} PUBLIC
    TENDRIL_VERSION="${PROJECT_VERSION}"
    TENDRIL_EXAMPLES_DIR="${PROJECT_SOURCE_DIR}/examples")
  set_target_properties(tendril_${name} PROPERTIES OUTPUT_NAME tendril_${name})
  # A precompiled header shared by every module (none in fuzzing builds, where the readers
  # are compiled with coverage and without it: core would then have no source that builds it
  # for the others to reuse).
  if(TENDRIL_BUILD_FUZZ)
  elseif(name STREQUAL "core")
    target_precompile_headers(tendril_core PRIVATE
      <vector> <string> <memory> <optional> <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>)
  else()
    target_precompile_headers(tendril_${name} REUSE_FROM tendril_core)
  endif()
  if(TENDRIL_BUILD_FUZZ)
    # Coverage where input is read and checked — the parsers, the scene, graph and session
    # readers, every model's saved-state reader — not in the simulations they start, whose
    # traced Eigen loops would run a hundred times slower (and without the precompiled header,
    # which is built without coverage).
    set(covered ${sources})
    list(FILTER covered INCLUDE REGEX "/(core|scene|graph|session|lsystem)/|(_state|_archive|_reader|/species|/mesh_import)\\.cpp$")
    set_source_files_properties(${covered} PROPERTIES
      COMPILE_OPTIONS "-fsanitize=fuzzer-no-link;-fsanitize-coverage-ignorelist=${PROJECT_SOURCE_DIR}/fuzz/coverage-ignorelist.txt"
      OBJECT_DEPENDS ${PROJECT_SOURCE_DIR}/fuzz/coverage-ignorelist.txt
      SKIP_PRECOMPILE_HEADERS ON)
  endif()
  set(TENDRIL_MODULES ${TENDRIL_MODULES} ${name} PARENT_SCOPE)
endfunction()

# Bottom to top. A module may use only modules listed before it, and only those it names.
tendril_module(core)
tendril_module(plant  DEPS core)
tendril_module(env    DEPS core PACKAGES embree assimp::assimp)
tendril_module(mesh   DEPS plant core PACKAGES meshoptimizer::meshoptimizer)
tendril_module(io     DEPS mesh plant core PACKAGES TinyGLTF::TinyGLTF PkgConfig::STB PkgConfig::OPENEXR)
tendril_module(models DEPS env plant core)
tendril_module(climb     DEPS models env plant core)
tendril_module(particles DEPS models env plant core)
tendril_module(lsystem   DEPS models env plant io core)
tendril_module(graph     DEPS models plant io core PACKAGES PkgConfig::MUPARSER)
tendril_module(wind   DEPS models env mesh io plant core)
# The scene reader names every model (scene/model_types.cpp, the table of models); its users,
# the Session and the apps, see the models only through models/ (PlantSystem, capabilities).
tendril_module(scene  DEPS wind models env core PRIVATE_DEPS climb particles lsystem graph)
tendril_module(session DEPS scene wind models env plant io core)
tendril_module(render DEPS session wind io mesh env plant core PACKAGES PkgConfig::EPOXY OpenGL::EGL)

# Built-in presets: examples/species/*.json compiled into core.
file(GLOB TENDRIL_EMBEDDED CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/examples/species/*.json)
set(TENDRIL_EMBEDDED_CPP ${PROJECT_BINARY_DIR}/generated/embedded_files.cpp)
string(REPLACE ";" "|" TENDRIL_EMBEDDED_ARG "${TENDRIL_EMBEDDED}")  # a ';' would split the argument
add_custom_command(OUTPUT ${TENDRIL_EMBEDDED_CPP}
  COMMAND ${CMAKE_COMMAND} "-DFILES=${TENDRIL_EMBEDDED_ARG}" -DROOT=${PROJECT_SOURCE_DIR}/examples
          -DOUTPUT=${TENDRIL_EMBEDDED_CPP} -P ${PROJECT_SOURCE_DIR}/cmake/EmbedFiles.cmake
  DEPENDS ${TENDRIL_EMBEDDED} ${PROJECT_SOURCE_DIR}/cmake/EmbedFiles.cmake
  COMMENT "Embedding built-in presets" VERBATIM)
target_sources(tendril_core PRIVATE ${TENDRIL_EMBEDDED_CPP})
set_source_files_properties(${TENDRIL_EMBEDDED_CPP} PROPERTIES SKIP_PRECOMPILE_HEADERS ON)

# Every module but the renderer (no OpenGL): what the CLI's growth and export need. The model
# implementations are linked, their headers not shown (see scene above).
add_library(tendril_lib INTERFACE)
target_link_libraries(tendril_lib INTERFACE tendril_session)
# With every module's headers: tests, benchmarks and fuzz targets, which look inside models.
add_library(tendril_all_headers INTERFACE)
target_link_libraries(tendril_all_headers INTERFACE tendril_climb tendril_particles tendril_lsystem tendril_graph)
# With the OpenGL renderer (EGL, epoxy): the studio, `tendril render`, render tests.
add_library(tendril_render_lib INTERFACE)
target_link_libraries(tendril_render_lib INTERFACE tendril_render tendril_lib)
