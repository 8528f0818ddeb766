# `cmake --install build/release [--prefix DIR]`: the semslam binary, the default vocabulary where the vocabulary
# lookup expects it (<prefix>/share/semslam/vocabulary, see place/vocabulary.h DefaultVocabularyPath), the model
# cards, the example configuration and the docs, and (python/CMakeLists.txt) the Python module.
include(GNUInstallDirs)
install(TARGETS semslam_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/data/vocabulary/semslam.voc ${PROJECT_SOURCE_DIR}/data/vocabulary/README.md
        DESTINATION ${CMAKE_INSTALL_DATADIR}/semslam/vocabulary COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models/ DESTINATION ${CMAKE_INSTALL_DATADIR}/semslam/models
        COMPONENT runtime FILES_MATCHING PATTERN "*.yaml" PATTERN "*.md")
install(FILES ${PROJECT_SOURCE_DIR}/config/default.yaml DESTINATION ${CMAKE_INSTALL_DATADIR}/semslam/config
        COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/docs/formats.md
              ${PROJECT_SOURCE_DIR}/docs/report.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT runtime)
