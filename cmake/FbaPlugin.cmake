# fba_add_plugin(<name> SOURCES <files...> [LIBRARIES <targets...>])
function(fba_add_plugin name)
endfunction()
