# ctsurg_require_npm_package(<folder> <package> <option> <what> <version-var>): the npm package that a
# build-time embed reads from <folder>/node_modules (pinned by <folder>'s package-lock.json;
# scripts/install-deps.sh runs npm ci there) must be installed at the version <folder>/package.json
# names, or configuring stops with what to do (run install-deps, or turn <option> OFF). A changed
# package.json or lock configures again, so a stale node_modules is caught here. Sets <version-var>.
function(ctsurg_require_npm_package folder package option what version_var)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${folder}/package.json ${folder}/package-lock.json)
  file(READ ${folder}/package.json wanted)
  string(JSON wanted GET "${wanted}" dependencies ${package})
  set(installed "none")
  if(EXISTS ${folder}/node_modules/${package}/package.json)
    file(READ ${folder}/node_modules/${package}/package.json installed)
    string(JSON installed GET "${installed}" version)
  endif()
  if(NOT installed STREQUAL wanted)
    message(FATAL_ERROR "${what} needs npm ${package} ${wanted} in ${folder}/node_modules (found: ${installed}): run "
                        "scripts/install-deps.sh (it runs npm ci there), or configure with -D${option}=OFF to build without it.")
  endif()
  set(${version_var} ${wanted} PARENT_SCOPE)
endfunction()
