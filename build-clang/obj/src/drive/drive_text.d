build-clang/obj/src/drive/drive_text.o: src/drive/drive_text.c \
  src/drive/drive_internal.h include/dfle/error.h

src/drive/drive_internal.h:

include/dfle/error.h:
