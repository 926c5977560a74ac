# Embeds examples/02_combined_elements/scene.json as the CLI's default demo scene, so the
# demo and the example are one file.
file(READ ${INPUT} TVF_DEFAULT_SCENE_TEXT)
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
