# Embeds the HTML viewer in ctsurg-render (run at build time by render/CMakeLists.txt, cmake -P):
# writes OUT, a C++ source holding the page template PAGE (render/viewer/viewer_page.html) and the
# viewer's script SCRIPT (npm @google/model-viewer's dist/model-viewer.min.js: one ES module with
# three.js and lit bundled, installed by scripts/install-deps.sh) as byte arrays, and the library's
# name and version from PACKAGE (its package.json). The page inlines the script in a <script> element,
# so the script must not contain "<script" or "</script" (the HTML parser would end or nest the
# element there): checked here. Its source map comment is dropped (nothing to fetch, even with the
# browser's developer tools open).
#   cmake -DPAGE=... -DSCRIPT=... -DPACKAGE=... -DOUT=... -P embed_viewer.cmake
foreach(var PAGE SCRIPT PACKAGE OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "embed_viewer.cmake: -D${var}=... is required")
  endif()
endforeach()

file(READ "${PACKAGE}" package_json)
string(JSON library_name GET "${package_json}" name)
string(JSON library_version GET "${package_json}" version)

file(READ "${SCRIPT}" script)
string(TOLOWER "${script}" lowered)
foreach(bad "<script" "</script")
  string(FIND "${lowered}" "${bad}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "embed_viewer.cmake: ${SCRIPT} contains '${bad}' at byte ${at}: it cannot be inlined in an HTML "
                        "<script> element as it is")
  endif()
endforeach()
string(REGEX REPLACE "\n//# sourceMappingURL=[^\n]*\n?$" "\n" script "${script}")
file(READ "${PAGE}" page)

# A string's bytes as a C++ initializer list: "0x3c,0x21,...".
function(bytes_of text out)
  string(HEX "${text}" hex)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," list "${hex}")
  set(${out} "${list}" PARENT_SCOPE)
endfunction()
bytes_of("${page}" page_bytes)
bytes_of("${script}" script_bytes)

file(WRITE "${OUT}.tmp"
  "// Generated at build time by render/viewer/embed_viewer.cmake from render/viewer/viewer_page.html and\n"
  "// ${library_name} ${library_version} (node_modules/${library_name}/dist/model-viewer.min.js). Do not edit.\n"
  "#include \"html_viewer_assets.h\"\n\n"
  "namespace ctsurg::html_viewer_assets {\n\n"
  "const char kLibrary[] = \"${library_name} ${library_version}\";\n"
  "const unsigned char kPage[] = {${page_bytes}};\n"
  "const std::size_t kPageSize = sizeof(kPage);\n"
  "const unsigned char kScript[] = {${script_bytes}};\n"
  "const std::size_t kScriptSize = sizeof(kScript);\n\n"
  "}  // namespace ctsurg::html_viewer_assets\n")
file(RENAME "${OUT}.tmp" "${OUT}")
