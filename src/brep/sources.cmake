# The brep module: OpenCASCADE B-rep construction and STEP writing.
list(APPEND NCREV_OCCT_SOURCES
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/check.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/planar.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/reverse.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/step.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/step_direct.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/surfaces.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/tangency.cpp
    ${CMAKE_CURRENT_SOURCE_DIR}/src/brep/deviation.cpp
)
list(APPEND NCREV_OCCT_LIBS
    TKernel TKMath TKG2d TKG3d TKGeomBase TKBRep TKGeomAlgo TKTopAlgo TKShHealing
    TKXSBase TKSTEPBase TKSTEPAttr TKSTEP209 TKSTEP TKMesh
    TKLCAF TKCAF TKXCAF TKXDESTEP
)
