# The sample module: machined parts with ground truth, built with OpenCASCADE.
list(APPEND NCREV_OCCT_SOURCES
    ${CMAKE_CURRENT_SOURCE_DIR}/src/sample/parts.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/sample/tessellate.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/sample/sample.cpp
)
list(APPEND NCREV_OCCT_LIBS
    TKernel TKMath TKG2d TKG3d TKGeomBase TKBRep TKGeomAlgo TKTopAlgo TKPrim TKBO TKBool
    TKFillet TKOffset TKShHealing TKMesh TKXSBase TKSTEPBase TKSTEPAttr TKSTEP209 TKSTEP
)
