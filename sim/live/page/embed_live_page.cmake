# Embeds ctsurg-live's page in the server (run at build time by sim/live/CMakeLists.txt, cmake -P):
# writes OUT, a C++ source implementing sim/live/src/live_page_assets.h, with these files of PAGE_DIR
# (sim/live/page) as byte arrays, in the order served:
#   ""                  live_page.html (the page, served at the session's URL itself)
#   live_page.js        the page's script (an ES module)
#   live_page.css       its style sheet
#   three.module.js     npm three's module build, which imports ./three.core.js
#   three.core.js
#   OrbitControls.js    three's camera controls (examples/jsm/controls), its `from 'three'` import
#                       rewritten to `from './three.module.js'`
# and library() = "three <version>" from node_modules/three/package.json. Every file lies beside the
# page under the session's URL, so relative imports resolve without an import map (the server's
# Content-Security-Policy allows no inline script). The import texts rewritten or relied on are checked
# here, so a three.js upgrade that changes them fails the build instead of the page. Source map comments
# are dropped (nothing to fetch, even with the browser's developer tools open).
#   cmake -DPAGE_DIR=... -DOUT=... -P embed_live_page.cmake
cmake_minimum_required(VERSION 3.25)
foreach(var PAGE_DIR OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "embed_live_page.cmake: -D${var}=... is required")
  endif()
endforeach()
set(three_dir "${PAGE_DIR}/node_modules/three")

file(READ "${three_dir}/package.json" package_json)
string(JSON three_version GET "${package_json}" version)

# `text` with `old` (which must occur exactly once) replaced by `new`.
function(replace_once text old new file out)
  string(FIND "${text}" "${old}" first)
  string(FIND "${text}" "${old}" last REVERSE)
  if(first EQUAL -1 OR NOT first EQUAL last)
    message(FATAL_ERROR "embed_live_page.cmake: ${file} does not contain \"${old}\" exactly once (three ${three_version}): "
                        "its imports changed; update embed_live_page.cmake and the page for this version")
  endif()
  string(REPLACE "${old}" "${new}" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# Fails unless every module that `text` imports from (an unindented `import ... from '...'`,
# `export ... from '...'`, `} from '...'` closing a multi-line import, or `import '...'`) is one of
# the specifiers after `file`: anything else would be a request the server cannot answer.
function(check_imports text file)
  set(statement "(^|\n)((import|export|})[^\n'\"]* from|import) *['\"]([^'\"]*)['\"]")
  string(REGEX MATCHALL "${statement}" imports "${text}")
  foreach(import IN LISTS imports)
    string(REGEX REPLACE "${statement}" "\\4" specifier "${import}")
    if(NOT specifier IN_LIST ARGN)
      message(FATAL_ERROR "embed_live_page.cmake: ${file} imports '${specifier}', which the page does not serve "
                          "(three ${three_version}); update embed_live_page.cmake for this version")
    endif()
  endforeach()
endfunction()

# A file's text without a trailing source map comment; it must not be empty (no zero-length array).
function(read_source file out)
  file(READ "${file}" text)
  if(text STREQUAL "")
    message(FATAL_ERROR "embed_live_page.cmake: ${file} is empty or missing")
  endif()
  string(REGEX REPLACE "\n//# sourceMappingURL=[^\n]*\n?$" "\n" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

read_source("${PAGE_DIR}/live_page.html" page)
read_source("${PAGE_DIR}/live_page.js" script)
read_source("${PAGE_DIR}/live_page.css" style)
read_source("${three_dir}/build/three.module.js" three_module)
read_source("${three_dir}/build/three.core.js" three_core)
read_source("${three_dir}/examples/jsm/controls/OrbitControls.js" orbit_controls)

check_imports("${script}" live_page.js ./three.module.js ./OrbitControls.js)
check_imports("${three_module}" three.module.js ./three.core.js)
check_imports("${three_core}" three.core.js)
replace_once("${orbit_controls}" "} from 'three';" "} from './three.module.js';" OrbitControls.js orbit_controls)
check_imports("${orbit_controls}" OrbitControls.js ./three.module.js)

# Appends the asset `name` (served as text/`kind`, UTF-8), the text in variable `var`, to the C++ arrays
# and table.
# The bytes go as an initializer list "0x3c,0x21,...": one HEX and one REGEX REPLACE per file, a few
# seconds for three.js's 2 MB.
set(arrays "")
set(table "")
function(add_asset name kind var)
  string(HEX "${${var}}" hex)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  string(APPEND arrays "const unsigned char k_${var}[] = {${bytes}};\n")
  string(APPEND table "    {\"${name}\", \"text/${kind}; charset=utf-8\", k_${var}},\n")
  set(arrays "${arrays}" PARENT_SCOPE)
  set(table "${table}" PARENT_SCOPE)
endfunction()
add_asset("" html page)
add_asset(live_page.js javascript script)
add_asset(live_page.css css style)
add_asset(three.module.js javascript three_module)
add_asset(three.core.js javascript three_core)
add_asset(OrbitControls.js javascript orbit_controls)

file(WRITE "${OUT}.tmp"
  "// Generated at build time by sim/live/page/embed_live_page.cmake from sim/live/page and npm three\n"
  "// ${three_version} (sim/live/page/node_modules/three). Do not edit.\n"
  "#include \"live_page_assets.h\"\n\n"
  "namespace ctsurg::sim::live_page {\n"
  "namespace {\n\n"
  "${arrays}\n"
  "const Asset kAssets[] = {\n${table}};\n\n"
  "}  // namespace\n\n"
  "std::span<const Asset> assets() { return kAssets; }\n\n"
  "std::string_view library() { return \"three ${three_version}\"; }\n\n"
  "}  // namespace ctsurg::sim::live_page\n")
file(RENAME "${OUT}.tmp" "${OUT}")
