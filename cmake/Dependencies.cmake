# Every third-party package Tendril uses, found once; cmake/Modules.cmake links each to the
# modules that use it. All are Debian 12 packages installed by scripts/setup.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(embree 3 REQUIRED)
find_package(TBB REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(assimp REQUIRED)
find_package(TinyGLTF REQUIRED)
find_package(spdlog REQUIRED)
find_package(fmt REQUIRED)
find_package(CLI11 REQUIRED)
# Levels of detail: simplification and vertex cache / fetch ordering (Debian's package ships a
# CMake config with the target meshoptimizer::meshoptimizer).
find_package(meshoptimizer REQUIRED)
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(MUPARSER REQUIRED IMPORTED_TARGET muparser)
pkg_check_modules(STB REQUIRED IMPORTED_TARGET stb)
# Pivot Painter textures (io/pivot_painter.h): RGBA half-float OpenEXR, which stb cannot write.
pkg_check_modules(OPENEXR REQUIRED IMPORTED_TARGET OpenEXR)
# Rendering: libepoxy loads the OpenGL entry points of whichever context is current (the
# studio's GLFW window or an EGL offscreen context); EGL makes headless contexts.
pkg_check_modules(EPOXY REQUIRED IMPORTED_TARGET epoxy)
find_package(OpenGL REQUIRED COMPONENTS EGL)

