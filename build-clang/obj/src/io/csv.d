build-clang/obj/src/io/csv.o: src/io/csv.c include/dfle/csv.h \
  include/dfle/error.h include/dfle/file.h

include/dfle/csv.h:

include/dfle/error.h:

include/dfle/file.h:
