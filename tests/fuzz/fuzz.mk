# fuzz.mk — the libFuzzer targets of tests/fuzz/ (included from the Makefile).
#   make fuzz-build                 build every target into build/fuzz/ (clang, libFuzzer,
#                                   ASan + UBSan; the project's sources compiled again with the
#                                   same flags into build/fuzz/obj/, never mixed with build/)
#   make fuzz [FUZZ_SECONDS=600]    run each target FUZZ_SECONDS seconds from its checked-in
#                                   corpus (tests/fuzz/corpus/NAME/, read only: new inputs go to
#                                   build/fuzz/work/NAME/); prints the executions per target and
#                                   fails when one finds a crash (kept in build/fuzz/crashes/)
#   make fuzz FUZZ_TARGETS="json svg"   only those
#   build/fuzz/fuzz_NAME FILE...    runs those inputs once (a crash kept in build/fuzz/crashes/,
#                                   or a corpus file); -help=1 for libFuzzer's flags
# tests/fuzz/run.sh does the runs (tests/t_fuzz.sh too); it holds each target's flags.

FUZZ_CC      ?= clang
FUZZ_BUILD   ?= build/fuzz
FUZZ_SECONDS ?= 600
FUZZ_SAN     := -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
                -fno-omit-frame-pointer
FUZZ_CFLAGS  := -std=c17 -O1 -g -Wall -Wextra -Werror -pthread -D_GNU_SOURCE $(FUZZ_SAN)
FUZZ_ALL     := $(patsubst tests/fuzz/fuzz_%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
FUZZ_TARGETS ?= $(FUZZ_ALL)
FUZZ_BIN     := $(FUZZ_ALL:%=$(FUZZ_BUILD)/fuzz_%)
FUZZ_HDR     := $(wildcard core/*.h api/*.h server/*.h tests/fuzz/*.h)
FUZZ_LIB_OBJ := $(CORE_SRC:%.c=$(FUZZ_BUILD)/obj/%.o) $(API_SRC:%.c=$(FUZZ_BUILD)/obj/%.o)
FUZZ_SRV_OBJ := $(SERVER_SRC:%.c=$(FUZZ_BUILD)/obj/%.o) $(FUZZ_BUILD)/obj/gen/openapi.o \
                $(FUZZ_BUILD)/obj/gen/web.o

.PHONY: fuzz-build
.SECONDARY: $(FUZZ_LIB_OBJ) $(FUZZ_SRV_OBJ) $(FUZZ_ALL:%=$(FUZZ_BUILD)/obj/tests/fuzz/fuzz_%.o)

fuzz-build: $(FUZZ_BIN)

$(FUZZ_BUILD)/obj/%.o: %.c $(FUZZ_HDR)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(CPPFLAGS) $(FUZZ_CFLAGS) -c $< -o $@

$(FUZZ_BUILD)/obj/gen/openapi.c: schemas/openapi.json scripts/embed.sh
	@mkdir -p $(dir $@)
	scripts/embed.sh cellar_openapi schemas/openapi.json > $@

$(FUZZ_BUILD)/obj/gen/openapi.o: $(FUZZ_BUILD)/obj/gen/openapi.c
	$(FUZZ_CC) $(FUZZ_CFLAGS) -c $< -o $@

# the page's assets, from the main build's bundle ($(BUILD)/web)
$(FUZZ_BUILD)/obj/gen/web.c: $(BUILD)/web/assets.list scripts/web-embed.sh
	@mkdir -p $(dir $@)
	scripts/web-embed.sh $(BUILD)/web > $@.tmp && mv $@.tmp $@

$(FUZZ_BUILD)/obj/gen/web.o: $(FUZZ_BUILD)/obj/gen/web.c server/webassets.h
	$(FUZZ_CC) $(CPPFLAGS) $(FUZZ_CFLAGS) -c $< -o $@

$(FUZZ_BUILD)/libcellar.a: $(FUZZ_LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(FUZZ_BUILD)/libcellard.a: $(FUZZ_SRV_OBJ)
	@rm -f $@
	ar rcs $@ $^

# every target links the daemon's library too: only fuzz_http uses it, the others take nothing
# from it (an archive gives only the members a target needs)
$(FUZZ_BUILD)/fuzz_%: $(FUZZ_BUILD)/obj/tests/fuzz/fuzz_%.o $(FUZZ_BUILD)/libcellard.a \
                      $(FUZZ_BUILD)/libcellar.a
	$(FUZZ_CC) $(FUZZ_CFLAGS) -o $@ $^ $(SERVER_LIBS) $(JANSSON_LIBS) $(LDLIBS)

fuzz: fuzz-build
	@tests/fuzz/run.sh --build $(FUZZ_BUILD) --seconds $(FUZZ_SECONDS) $(FUZZ_TARGETS)
