/* The healing skin as tissue, shared by the two wound paths (`skinsim
 * abrasion`'s optics palette, src/abrasion/palette.c, and `skinsim wound`'s
 * per-texel table lookup, src/wound/render.c), so that both draw the same
 * new epithelium and the same post-inflammatory hyperpigmentation:
 *
 *   new epithelium     a thin epidermis (SS_NEW_EPIDERMIS_FRACTION of the
 *                      skin's) with the skin's melanin times a factor (its
 *                      melanocytes repopulate it over weeks), over young,
 *                      hyperaemic dermis (blood SS_YOUNG_DERMIS_BLOOD, 4x-8x
 *                      a healthy dermis's, at SS_YOUNG_DERMIS_OXYGENATION):
 *                      pink on light skin, pink-brown on dark. As tissue, not
 *                      a colour: abrasion renders it with its Kubelka-Munk
 *                      layers, wound with the ModelMatch table (the Monte
 *                      Carlo transport), each its own way of rendering the
 *                      skin around it;
 *   PIH rate           the fraction of patients with post-inflammatory
 *                      hyperpigmentation after an inflammatory skin injury,
 *                      by the skin's individual typology angle (the strength
 *                      of the healed skin's hyperpigmentation in both);
 *   PIH course         its time course after closure (ss_pih_course, fitted
 *                      to Danielsen et al. 2013) and the melanin factor it
 *                      gives (ss_pih_melanin_factor): one curve, so the two
 *                      paths darken a healed dark skin alike on every day;
 *   repigmentation     the rest of the healed epidermis's melanin
 *                      (ss_repigmentation_factor): melanin-poor new
 *                      epithelium repigmenting over a week, then the mature
 *                      scar a little lighter; with PIH, the one melanin
 *                      factor of both paths (ss_healed_melanin_factor).
 *
 * Gave up: one colour for both paths (abrasion's Kubelka-Munk palette in
 * `wound` too): `wound` draws the skin around the wound through the table,
 * texel by texel with the bio map's own melanin and blood, and its recipe's
 * young_blood and new_epidermis change the tissue; a palette colour would
 * be a second transport beside the table's (a* 5 lower at the same tissue)
 * and flat where the skin is mottled. */
#include <math.h>

#include "skinsim/optics.h"

void ss_bio_new_epithelium(const ss_bio_params *skin, double melanin_factor, ss_bio_params *out) {
    *out = *skin;
    out->melanin = skin->melanin * melanin_factor;
    out->epidermis_thickness_cm = skin->epidermis_thickness_cm * SS_NEW_EPIDERMIS_FRACTION;
    out->blood = SS_YOUNG_DERMIS_BLOOD;
    out->oxygenation = SS_YOUNG_DERMIS_OXYGENATION;
}

/* Post-inflammatory hyperpigmentation by skin type: the fraction of patients
 * with it after an inflammatory skin injury, from the individual typology
 * angle of the skin (Chardon, Cretois & Hourseau 1991, Int. J. Cosmet. Sci. 13:
 * 191: very light > 55 deg, light 41-55, intermediate 28-41, tan 10-28, brown
 * -30-10, dark < -30). Rates: acne patients of colour, Taylor, Cook-Bolden,
 * Rahman & Strachan 2002, J. Am. Acad. Dermatol. 46: S98 (PIH in 65 % of
 * African-American, 53 % of Hispanic and 47 % of Asian patients); light skin
 * types I-III rarely (a few per cent; Davis & Callender 2010, J. Clin. Aesthet.
 * Dermatol. 3(7): 20). Interpolated linearly in ITA between the class
 * centres. */
double ss_pih_prevalence(double ita_deg) {
    static const double ita[6] = {-45, -10, 19, 34.5, 48, 62};
    static const double p[6] = {0.65, 0.53, 0.47, 0.25, 0.08, 0.03};
    if (ita_deg <= ita[0]) return p[0];
    for (int k = 0; k < 5; k++)
        if (ita_deg <= ita[k + 1]) {
            double t = (ita_deg - ita[k]) / (ita[k + 1] - ita[k]);
            return p[k] + (p[k + 1] - p[k]) * t;
        }
    return p[5];
}

/* The course of post-inflammatory hyperpigmentation after closure: in
 * split-thickness donor sites (Danielsen, Jorgensen, Jorgensen, Karlsmark &
 * Agren 2013, "Erythema persists longer than one year in split-thickness skin
 * graft donor sites", Acta Derm. Venereol. 93: 281) pigmentation was 24 %
 * above the adjacent skin at 1 month, 15 % at 3 months and back to it at 12.
 * Shape A (1 - exp(-t / rise)) exp(-t / fade): the rise over two weeks is
 * ours (PIH follows the inflammation, none at closure; not measured there),
 * A and fade are solved so the curve passes through both measurements
 * exactly (fade 101 d, A 0.366; 0.010 at 365 d, "back"). */
#define PIH_RISE_DAYS 14.0
#define PIH_AT_1M 0.24
#define PIH_AT_3M 0.15

double ss_pih_course(double days) {
    if (!(days > 0)) return 0;
    double r1 = 1 - exp(-30.0 / PIH_RISE_DAYS), r3 = 1 - exp(-90.0 / PIH_RISE_DAYS);
    double fade = 60.0 / log(PIH_AT_1M / PIH_AT_3M * r3 / r1);
    double a = PIH_AT_1M / (r1 * exp(-30.0 / fade));
    return a * (1 - exp(-days / PIH_RISE_DAYS)) * exp(-days / fade);
}

double ss_pih_melanin_factor(double prevalence, double days, double gain) {
    return 1 + gain * prevalence * ss_pih_course(days);
}

/* Repigmentation and the scar's melanin. New epithelium is melanin-poor:
 * melanocytes migrate in from the wound margin and the surviving follicles
 * over the first weeks (Chadwick, Heath & Shah 2012, "Abnormal pigmentation
 * within cutaneous scars: a complication of wound healing", Indian J. Plast.
 * Surg. 45: 403; its pattern varies from patient to patient); by a month the
 * donor sites' pigmentation was back and above the adjacent skin's
 * (Danielsen et al. 2013, above), so the repigmentation is near complete
 * within that month (0.5 at closure, 10 days: ours, no clinical time constant
 * found). The mature scar is paler than the skin, but mostly for optical and
 * vascular reasons: pale surgical scars hold as many melanocytes, with melanin
 * transferred as in the adjacent skin (Velangi & Rees 2001, "Why are scars
 * pale?", Acta Derm. Venereol. 81: 326), and hypo- and hyperpigmented parts of
 * burn scars the same melanocyte numbers at different activity (Carney et al.
 * 2021, PLoS One 16: e0248985). So the scar's melanin loss is modest (a
 * quarter, after the first month, over five months; the whitening of its
 * dense collagen is each path's own optics), and at a year a dark skin's scar
 * is slightly lighter than the skin or similar, as in the clinical picture. */
void ss_repigmentation_default(ss_repigmentation *p) {
    p->new_melanin = SS_REPIG_NEW_MELANIN;
    p->repig_days = SS_REPIG_DAYS;
    p->scar_melanin = SS_REPIG_SCAR_MELANIN;
}

double ss_repigmentation_factor(const ss_repigmentation *p, double days) {
    double t = days > 0 ? days : 0;
    double repig = p->new_melanin + (1 - p->new_melanin) * (1 - exp(-t / p->repig_days));
    double pale = 1 - exp(-fmax(0.0, t - SS_SCAR_PALE_DELAY_DAYS) / SS_SCAR_PALE_DAYS);
    return repig * (1 - (1 - p->scar_melanin) * pale);
}

double ss_healed_melanin_factor(const ss_repigmentation *p, double prevalence, double gain,
                                double days) {
    return ss_repigmentation_factor(p, days) * ss_pih_melanin_factor(prevalence, days, gain);
}
