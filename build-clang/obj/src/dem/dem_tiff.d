build-clang/obj/src/dem/dem_tiff.o: src/dem/dem_tiff.c src/dem/dem_tiff.h

src/dem/dem_tiff.h:
