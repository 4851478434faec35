# cmake -DSOURCE=node_modules/three -DDEST=dir -DFILES=a;b -P vendor_three.cmake
# Copies FILES (paths inside the three package) from SOURCE to DEST. In the ES modules, the bare
# specifier of `from 'three'` (resolved by bundlers or an import map) becomes the relative path
# of build/three.module.js, so browsers resolve it with no import map.
foreach(f IN LISTS FILES)
  get_filename_component(dir ${DEST}/${f} DIRECTORY)
  file(MAKE_DIRECTORY ${dir})
  if(f MATCHES "\\.js$")
    file(READ ${SOURCE}/${f} text)
    file(RELATIVE_PATH module ${dir} ${DEST}/build/three.module.js)
    if(NOT module MATCHES "^\\.")
      set(module "./${module}")
    endif()
    string(REPLACE "from 'three';" "from '${module}';" text "${text}")
    file(WRITE ${DEST}/${f}.tmp "${text}")
    file(COPY_FILE ${DEST}/${f}.tmp ${DEST}/${f} ONLY_IF_DIFFERENT)
    file(REMOVE ${DEST}/${f}.tmp)
  else()
    file(COPY_FILE ${SOURCE}/${f} ${DEST}/${f} ONLY_IF_DIFFERENT)
  endif()
endforeach()
