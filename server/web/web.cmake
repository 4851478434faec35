# The web page (server/web/), embedded into mdn_http at build time; included by
# server/http/CMakeLists.txt, which adds ${MDN_WEB_EMBEDDED_CPP} to the library.
#
# - The page's own files (*.html, *.css, *.js, *.svg here) are served at /web/<name>.
# - three.js comes from npm, pinned by server/web/package-lock.json and installed into
#   server/web/node_modules by `npm ci` (scripts/install-deps.sh build). Only the files the page
#   imports are embedded, at /web/vendor/three/<path in the package>; their bare `from 'three'`
#   imports are rewritten to relative paths (vendor_three.cmake), so the page needs no import map
#   (an inline script the Content-Security-Policy would have to allow).
set(MDN_WEB_DIR ${PROJECT_SOURCE_DIR}/server/web)
set(MDN_THREE_DIR ${MDN_WEB_DIR}/node_modules/three)

# The installed three.js must be the locked one: a stale node_modules would embed another version.
file(READ ${MDN_WEB_DIR}/package-lock.json mdn_web_lock)
string(JSON mdn_three_locked GET "${mdn_web_lock}" packages node_modules/three version)
set(mdn_three_installed "(none)")
if(EXISTS ${MDN_THREE_DIR}/package.json)
  file(READ ${MDN_THREE_DIR}/package.json mdn_three_package)
  string(JSON mdn_three_installed GET "${mdn_three_package}" version)
endif()
if(NOT mdn_three_installed STREQUAL mdn_three_locked)
  message(FATAL_ERROR "server/web/node_modules has three ${mdn_three_installed}, the lock file pins "
                      "${mdn_three_locked}: run `npm ci --prefix server/web` "
                      "(scripts/install-deps.sh build does it)")
endif()
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
             ${MDN_WEB_DIR}/package-lock.json ${MDN_THREE_DIR}/package.json)

# What the page imports from three.js (and the decoder DRACOLoader fetches), package-relative.
set(MDN_THREE_FILES
  LICENSE
  build/three.module.js
  build/three.core.js
  examples/jsm/controls/OrbitControls.js
  examples/jsm/loaders/GLTFLoader.js
  examples/jsm/loaders/DRACOLoader.js
  examples/jsm/loaders/OBJLoader.js
  examples/jsm/loaders/PLYLoader.js
  examples/jsm/loaders/STLLoader.js
  examples/jsm/utils/BufferGeometryUtils.js
  examples/jsm/utils/SkeletonUtils.js
  examples/jsm/libs/draco/draco_decoder.wasm
  examples/jsm/libs/draco/draco_wasm_wrapper.js
  examples/jsm/libs/meshopt_decoder.module.js)

set(mdn_vendor_dir ${CMAKE_CURRENT_BINARY_DIR}/web/vendor/three)
set(mdn_vendor_inputs "")
set(mdn_vendor_outputs "")
set(mdn_vendor_names "")
set(mdn_vendor_paths "")
foreach(f IN LISTS MDN_THREE_FILES)
  list(APPEND mdn_vendor_inputs ${MDN_THREE_DIR}/${f})
  list(APPEND mdn_vendor_outputs ${mdn_vendor_dir}/${f})
  string(MAKE_C_IDENTIFIER "three_${f}" name)
  list(APPEND mdn_vendor_names ${name})
  list(APPEND mdn_vendor_paths /web/vendor/three/${f})
endforeach()
add_custom_command(
  OUTPUT ${mdn_vendor_outputs}
  COMMAND ${CMAKE_COMMAND} -DSOURCE=${MDN_THREE_DIR} -DDEST=${mdn_vendor_dir} "-DFILES=${MDN_THREE_FILES}"
          -P ${MDN_WEB_DIR}/vendor_three.cmake
  DEPENDS ${mdn_vendor_inputs} ${MDN_WEB_DIR}/vendor_three.cmake
  COMMENT "Copying three.js ${mdn_three_locked} for the web page"
  VERBATIM)

file(GLOB MDN_WEB_PAGE_FILES CONFIGURE_DEPENDS
  ${MDN_WEB_DIR}/*.html ${MDN_WEB_DIR}/*.css ${MDN_WEB_DIR}/*.js ${MDN_WEB_DIR}/*.svg)
set(mdn_page_names "")
set(mdn_page_paths "")
foreach(f IN LISTS MDN_WEB_PAGE_FILES)
  get_filename_component(base ${f} NAME)
  string(MAKE_C_IDENTIFIER "page_${base}" name)
  list(APPEND mdn_page_names ${name})
  list(APPEND mdn_page_paths /web/${base})
endforeach()

# Two generated sources: the page changes often and is small; three.js (2.8 MB) rarely.
function(mdn_embed_web table comment)
  cmake_parse_arguments(ARG "" "" "INPUTS;NAMES;PATHS" ${ARGN})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/embedded_${table}.cpp)
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${out} "-DINPUTS=${ARG_INPUTS}" "-DNAMES=${ARG_NAMES}"
            -DTABLE=${table} "-DPATHS=${ARG_PATHS}" -P ${PROJECT_SOURCE_DIR}/server/http/embed_files.cmake
    DEPENDS ${ARG_INPUTS} ${PROJECT_SOURCE_DIR}/server/http/embed_files.cmake
    COMMENT "${comment}"
    VERBATIM)
endfunction()
mdn_embed_web(web_page_files "Embedding the web page (server/web/)"
  INPUTS ${MDN_WEB_PAGE_FILES} NAMES ${mdn_page_names} PATHS ${mdn_page_paths})
mdn_embed_web(web_vendor_files "Embedding three.js ${mdn_three_locked} for the web page"
  INPUTS ${mdn_vendor_outputs} NAMES ${mdn_vendor_names} PATHS ${mdn_vendor_paths})
set(MDN_WEB_EMBEDDED_CPP ${CMAKE_CURRENT_BINARY_DIR}/embedded_web_page_files.cpp
                         ${CMAKE_CURRENT_BINARY_DIR}/embedded_web_vendor_files.cpp)
