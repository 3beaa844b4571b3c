/* libFuzzer: MCML input files (`optics mci`), through ss_mci_parse, and the
 * run-output names through ss_path_under (which must refuse every name
 * leaving the folder). Runs are not simulated (that is Monte Carlo work, not
 * parsing). */
#include "fuzz_util.h"
#include "skinsim/optics.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = fuzz_text(data, size);
    if (!text) return 0;
    ss_mci_file mf;
    ss_error err;
    if (ss_mci_parse(text, "fuzz.mci", &mf, &err) == SS_OK) {
        for (int r = 0; r < mf.nruns; r++) {
            char *p = NULL;
            if (ss_path_under("/tmp", mf.runs[r].out_name, 0, &p, &err) == SS_OK &&
                strncmp(p, "/tmp/", 5) != 0)
                abort(); /* a name escaped the folder */
            free(p);
        }
        ss_mci_file_free(&mf);
    }
    free(text);
    return 0;
}
